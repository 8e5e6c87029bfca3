"""The loop's phase stage: the transitions each tick makes on its own.

The operator's actions move the phase from their threads
(:mod:`gcs.loop._actions`); the tick moves it where the fleet's state says so:
ready once every vehicle is heard (and the analysis passes), landed once every
vehicle disarmed, aborting when a safety rule lands the team, formation once
the payload is lifted, hover once it is set down, landing once the abort's hold
is over.
"""

from __future__ import annotations

import numpy as np

from gcs.analysis import Analysis
from gcs.config import Team
from gcs.loop._actions import ActionRunner
from gcs.loop._events import EventLog
from gcs.loop._fleet import FleetState
from gcs.loop._operator import OperatorSnapshot
from gcs.loop._phase_machine import PhaseMachine
from gcs.loop._phases import Phase
from gcs.loop._reached import AltitudeReached
from gcs.loop._safety import SafetyVerdict

__all__ = ["PhaseStage"]


class PhaseStage:
    """The tick's own phase transitions (see the module's docstring)."""

    def __init__(self, team: Team, analysis: Analysis, *, phases: PhaseMachine,
                 actions: ActionRunner, events: EventLog) -> None:
        self._team = team
        self._analysis = analysis
        self._phases = phases
        self._actions = actions
        self._events = events
        self.analysis_override = False
        """Fly although the analysis fails (``--override-analysis``): the user's call."""
        self._reached = AltitudeReached()  # the lift's or the set-down's altitude
        self._reached_in: Phase | None = None

    def settle(self, phase: Phase, fleet: FleetState, verdict: SafetyVerdict) -> Phase:
        """Before the motion: ready, landed, or the abort a safety rule asks for; the
        phase the tick goes on in."""
        if phase is Phase.CONNECT:
            self._preflight(fleet)
        elif phase is Phase.LANDING and np.all(np.isfinite(fleet.heartbeat_age)) \
                and not fleet.armed.any():
            self._phases.set(Phase.LANDED)
        if verdict.land and phase.airborne and phase not in (Phase.ABORTING, Phase.LANDING):
            self._actions.abort()
            phase = self._phases.phase
        return phase

    def advance(self, phase: Phase, op: OperatorSnapshot, now: float,
                fleet: FleetState) -> None:
        """After the setpoints: the lift or the set-down done once the ramp ended and the
        team is there (a team held up, vehicles in hold after a gap, is not), and the
        abort's hold over."""
        target = min(op.altitude_target, self._team.config.safety.geofence_altitude)
        if phase is not self._reached_in:
            self._reached_in = phase
            self._reached.reset()
        there = self._reached.update(-fleet.p_ned[:, 2], target,
                                     self._team.config.flight.altitude_tolerance)
        reached = abs(op.altitude - op.altitude_target) < 1e-6 and there
        if phase is Phase.LIFTING and reached:
            self._phases.set(Phase.FORMATION)
        elif phase is Phase.SETTING_DOWN and reached:
            self._phases.set(Phase.HOVER)
        elif (phase is Phase.ABORTING and self._phases.abort_at is not None
              and now - self._phases.abort_at >= self._team.config.flight.abort_hold):
            self._phases.abort_at = None
            self._phases.set(Phase.LANDING)
            self._actions.land()

    def _preflight(self, fleet: FleetState) -> None:
        fresh = np.isfinite(fleet.age) & (fleet.age < self._team.config.safety.stale_after)
        if fresh.all() and np.all(np.isfinite(fleet.heartbeat_age)):
            if not self._analysis.ok and not self.analysis_override:
                self._events.warn_once(("analysis", 0), "pre-flight: gcs analyze fails: " +
                                       self._analysis.violations[0].message)
                return
            self._phases.set(Phase.READY)
