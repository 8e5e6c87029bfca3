"""Flight phases of a transport and which operator action leads where.

    CONNECT -> READY -> ARMED -> TAKING_OFF -> HOVER -> LIFTING -> FORMATION
                                              ^                    |
                                              +--- SETTING_DOWN <--+
    HOVER/ARMED/... -> LANDING -> LANDED;  any -> ABORTING -> LANDING

* CONNECT: waiting for every configured vehicle; READY once the pre-flight
  checks pass (all present and fresh, ``gcs analyze`` passes for the config).
* TAKING_OFF climbs to just below the altitude where the ropes become taut
  (the payload still on the ground), then switches the vehicles to offboard.
* HOVER streams setpoints holding the shape with the payload on the ground.
* LIFTING raises the team by the lift height; FORMATION is operator flight;
  SETTING_DOWN lowers the team until the payload rests, back to HOVER.
* ABORTING freezes the motion (every vehicle holds) and then lands. An abort
  while aborting or landing keeps the phase: a held key's auto-repeat or a
  second viewer's press must neither restart the hold nor call a landing team
  back up into the hold (landing is where every abort ends).
* RESUME keeps the phase: it switches the vehicles that left the streaming mode
  on their own (a HOLD after a gap in the setpoints, a pilot's switch) back to
  it, so the frozen motion can go on.

This module is pure state: the runtime performs the actions.
"""

from __future__ import annotations

import enum

__all__ = ["Action", "Phase", "PhaseError", "next_phase"]


class Phase(enum.IntEnum):
    """Where the flight is; the integer is what the recorder logs."""

    CONNECT = 0
    READY = 1
    ARMED = 2
    TAKING_OFF = 3
    HOVER = 4
    LIFTING = 5
    FORMATION = 6
    SETTING_DOWN = 7
    LANDING = 8
    LANDED = 9
    ABORTING = 10

    @property
    def text(self) -> str:
        """Human-readable name."""
        return self.name.lower().replace("_", " ")

    @property
    def streaming(self) -> bool:
        """True while the GCS streams formation setpoints."""
        return self in (Phase.HOVER, Phase.LIFTING, Phase.FORMATION, Phase.SETTING_DOWN,
                        Phase.ABORTING)

    @property
    def airborne(self) -> bool:
        """True while vehicles may be in the air."""
        return self in (Phase.TAKING_OFF, Phase.HOVER, Phase.LIFTING, Phase.FORMATION,
                        Phase.SETTING_DOWN, Phase.ABORTING, Phase.LANDING)


class Action(enum.Enum):
    """What an operator (button, hotkey, gamepad, scenario) can ask for."""

    ARM = "arm"
    DISARM = "disarm"
    TAKEOFF = "takeoff"
    LIFT = "lift"
    SET_DOWN = "set_down"
    LAND = "land"
    ABORT = "abort"
    RESUME = "resume"

    @property
    def text(self) -> str:
        """Human-readable verb."""
        return {"takeoff": "take off", "set_down": "set down"}.get(self.value, self.value)


class PhaseError(RuntimeError):
    """An action that makes no sense in the current phase."""


_ALLOWED: dict[Action, tuple[frozenset[Phase], Phase | None]] = {  # None: stays
    Action.ARM: (frozenset({Phase.READY}), Phase.ARMED),
    Action.DISARM: (frozenset({Phase.ARMED, Phase.LANDED}), Phase.READY),
    Action.TAKEOFF: (frozenset({Phase.ARMED}), Phase.TAKING_OFF),
    Action.LIFT: (frozenset({Phase.HOVER}), Phase.LIFTING),
    Action.SET_DOWN: (frozenset({Phase.FORMATION, Phase.LIFTING}), Phase.SETTING_DOWN),
    Action.LAND: (frozenset({Phase.ARMED, Phase.HOVER, Phase.TAKING_OFF, Phase.ABORTING}),
                  Phase.LANDING),
    Action.ABORT: (frozenset(Phase) - {Phase.CONNECT, Phase.READY, Phase.LANDED},
                   Phase.ABORTING),  # but stays in ABORTING and LANDING (_STAYS)
    Action.RESUME: (frozenset({Phase.HOVER, Phase.LIFTING, Phase.FORMATION,
                               Phase.SETTING_DOWN}), None),
}


_STAYS: dict[Action, frozenset[Phase]] = {
    Action.ABORT: frozenset({Phase.ABORTING, Phase.LANDING}),
}
"""Phases where an allowed action keeps the phase: it is already where the action leads."""


def next_phase(phase: Phase, action: Action) -> Phase:
    """The phase an action leads to; PhaseError (with the reason) when not allowed."""
    allowed, target = _ALLOWED[action]
    if phase not in allowed:
        options = ", ".join(sorted(p.text for p in allowed))
        raise PhaseError(f"cannot {action.text} while {phase.text} "
                         f"(possible when: {options})")
    if target is None or phase in _STAYS.get(action, ()):
        return phase
    return target
