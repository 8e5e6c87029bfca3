"""The loop's safety stage: this tick's verdict, and what the team does about it.

The rules themselves are :func:`gcs.loop._safety.evaluate` (each enforced
there and nowhere else); this stage feeds them the tick's fleet, the mode rule
where it applies, and the safe radius for the acceleration last commanded. It
then re-engages vehicles that dropped to hold on a setpoint gap
(:mod:`gcs.loop._recovery`), holds, re-forms or lands a team deformed beyond the
safe bound (:mod:`gcs.loop._deformation`), and reports each rule once while it holds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from gcs.analysis import Analysis, a_safe_span
from gcs.config import Team
from gcs.link import AutopilotProfile, SetpointStream
from gcs.loop._actions import ActionRunner
from gcs.loop._clock import Clock
from gcs.loop._deformation import Deformation, DeformationPolicy
from gcs.loop._events import EventLog
from gcs.loop._fleet import FleetState
from gcs.loop._phase_machine import PhaseMachine
from gcs.loop._phases import Action, Phase
from gcs.loop._recovery import Recovery
from gcs.loop._safety import SafetyVerdict, evaluate
from gcs.loop._vehicle_modes import VehicleModes
from gcs.wire import StatusText, TelemetryRecord

__all__ = ["GAP_S", "ON_GCS_SETPOINTS", "SafetyStage"]

GAP_S = 0.3
"""Time without a setpoint round after which the vehicles may have dropped to hold, s of the
loop's clock (their timeout is 0.5 s: the stream may have stopped before the loop noticed)."""

ON_GCS_SETPOINTS = frozenset({Phase.HOVER, Phase.LIFTING, Phase.FORMATION,
                              Phase.SETTING_DOWN})
"""Phases in which every vehicle must stay in the mode that flies the GCS's setpoints."""

_CONNECTING = SafetyVerdict(freeze=True, land=False, events=())
"""The verdict before the team is ready: presence is the pre-flight check's business."""


class SafetyStage:
    """Judges each tick (:meth:`judge`); holds the recovery and the deformation policy."""

    def __init__(self, team: Team, analysis: Analysis, profiles: Mapping[int, AutopilotProfile],
                 *, clock: Clock, modes: VehicleModes, stream: SetpointStream,
                 actions: ActionRunner, phases: PhaseMachine, events: EventLog) -> None:
        self._team = team
        self._ids = team.formation.ids
        self.analysis = analysis
        self._clock = clock
        self._modes = modes
        self._stream = stream
        self._actions = actions
        self._phases = phases
        self._events = events
        safety = team.config.safety
        self.recovery = Recovery(automatic=safety.recovery == "auto",
                                 settle=safety.recover_after)
        """Re-engages vehicles that dropped to hold on a setpoint gap."""
        self.deformation = DeformationPolicy(growth=safety.deformed_land_growth)
        """Hold, re-form or land a team deformed beyond the safe bound."""
        self.shape = Deformation.NONE
        """What the team deformed beyond the bound does now."""
        self._active: set[tuple[str, int]] = set()
        for vid in self._ids:  # a vehicle saying its setpoints stopped
            profiles[vid].link.add_record_listener(self._on_record)

    def safe_radius_for(self, accel: float) -> float:
        """Largest vehicle-to-centroid distance at which ``accel`` (m/s^2) is still available.

        The analysis' safe deformation is this bound at the largest acceleration
        the guidance may command; the loop applies it to the acceleration it does
        command (the larger of the last tick's and a floor of a quarter of the
        limit), so a gently flown team may deform more before its motion freezes.
        """
        a = self.analysis
        cfg = self._team.config
        demand = max(accel, 0.25 * cfg.limits.accel_norm)
        return 0.5 * a_safe_span(a.horizontal_force, cfg.airframe.mass, demand,
                                 a.rope_pull_bound, cfg.payload.rope_length)

    def judge(self, now: float, phase: Phase, fleet: FleetState, *,
              commanded: float) -> SafetyVerdict:
        """This tick's verdict on ``fleet`` in ``phase``, ``commanded`` the largest
        acceleration the last tick sent (m/s^2); recovery and deformation acted on it."""
        if phase is Phase.CONNECT:
            verdict = _CONNECTING
        else:
            # The mode rule, only where it applies and some vehicle is out of its mode
            # (one tuple comparison per tick otherwise).
            modes: tuple[str, ...] = ()
            coming_down = None
            if phase in ON_GCS_SETPOINTS and fleet.modes != self._modes.streaming:
                modes = fleet.modes
                coming_down = self._modes.coming_down(fleet)
            verdict = evaluate(self._team.config.safety, self._ids, fleet.age, fleet.p_ned,
                               safe_radius=self.safe_radius_for(commanded), modes=modes,
                               expected=self._modes.streaming if modes else (),
                               coming_down=coming_down)
            self._recover(now, fleet, verdict, modes, coming_down)
            self.shape = self._watch_deformation(now, fleet, verdict, phase)
        self._report(verdict)
        return verdict

    def _recover(self, now: float, fleet: FleetState, verdict: SafetyVerdict,
                 modes: tuple[str, ...], coming_down: np.ndarray | None) -> None:
        """Re-engage the vehicles that dropped out of the streaming mode, once the team is
        healthy again (:mod:`gcs.loop._recovery`)."""
        out: tuple[int, ...] = ()
        if modes and coming_down is not None:
            out = self._modes.out_flying(self._ids, modes, coming_down)
        fresh = bool(np.all(fleet.age <= self._team.config.safety.stale_after))
        gap = self._stream.take_gap()
        last = self._stream.last_round
        if not fresh or gap or (math.isfinite(last) and now - last > GAP_S):
            self.recovery.note_gap(now)
        healthy = fresh and fleet.located and not verdict.hold and not verdict.land
        if not self.recovery.update(now, out=out, healthy=healthy):
            return
        # an action running (a resume among them): the next try comes later
        self._actions.try_start(
            Action.RESUME, self._phases.phase,
            say=f"recovery: every link fresh for {self.recovery.settle:g} s: re-engaging "
                f"vehicles {', '.join(map(str, self.recovery.after_gap))}")

    def _on_record(self, record: TelemetryRecord) -> None:
        """A vehicle's failsafe message about lost setpoints is a gap (a link's thread): it
        left its mode because of the stream, not because someone switched it."""
        if isinstance(record, StatusText) and record.setpoints_lost:
            self.recovery.note_gap(self._clock.now())

    def _watch_deformation(self, now: float, fleet: FleetState, verdict: SafetyVerdict,
                           phase: Phase) -> Deformation:
        """Hold, re-form or land a team deformed beyond the safe bound."""
        policy = self.deformation
        p = fleet.p_ned[:, :2]
        fresh = bool(np.all(fleet.age <= self._team.config.safety.stale_after))
        if policy.observe(p, fleet.v_ned[:, :2], fleet.t - fleet.age,
                          in_shape=fresh and fleet.located and not verdict.hold):
            self._events.warn_once(("jump", 0), "a vehicle's position jumped: a deformation "
                                                "from here on is held, not re-formed")
        else:
            self._events.unlatch(("jump", 0))
        before = self.shape
        shape = policy.update(now, deformed=verdict.hold, deformation=verdict.deformation, p_xy=p)
        if shape is Deformation.LAND and phase.airborne \
                and phase not in (Phase.ABORTING, Phase.LANDING):
            self._events.add("error", f"deformation grew from {policy.held_at:.2f} to "
                                      f"{verdict.deformation:.2f} m: landing the team")
            self._actions.abort()
        elif shape is Deformation.REFORM and before is not Deformation.REFORM:
            self._events.add("warning", "re-forming the shape (motion frozen): the team was "
                                        "in shape and no position jumped, so the positions "
                                        "are trusted")
        return shape

    def _report(self, verdict: SafetyVerdict) -> None:
        """Each rule's event once while it holds, again after it cleared."""
        active = set()
        for e in verdict.events:
            key = (e.reason.name, e.vehicle)
            active.add(key)
            if key not in self._active:
                self._events.add("warning", e.text)
        self._active = active
