"""The phase stage (gcs.loop._phase_stage) on a real loop over scripted ArduPilot links: the
transitions each tick makes on its own."""

from __future__ import annotations

import numpy as np

from gcs.guidance import MotionDemand
from gcs.loop import OperatorSnapshot, Phase
from gcs.loop._safety import SafetyVerdict
from tests.support.scripted_autopilot import HOVER_THRUST, fleet_state, peer_team

ARDUPILOTS = {vid: ("ardupilot", {}) for vid in (1, 2, 3, 4)}
FLOWING = SafetyVerdict(freeze=False, land=False, events=())
LAND = SafetyVerdict(freeze=True, land=True, events=())


def _at(altitude: float, target: float) -> OperatorSnapshot:
    return OperatorSnapshot(demand=MotionDemand(), altitude=altitude, altitude_target=target,
                            scale_target=1.0, guidance_on=True, source="test")


def test_a_heard_team_is_ready_and_a_rule_that_lands_aborts_a_flying_one() -> None:
    with peer_team(ARDUPILOTS) as bench:
        runtime, team = bench.runtime, bench.team
        stage = runtime.stages.phase
        fleet = fleet_state(team.formation.positions, HOVER_THRUST)
        assert stage.settle(Phase.CONNECT, fleet, FLOWING) is Phase.CONNECT
        assert runtime.phase is Phase.READY
        runtime.phases.set(Phase.FORMATION)
        assert stage.settle(Phase.FORMATION, fleet, LAND) is Phase.ABORTING


def test_a_landing_team_is_landed_once_every_vehicle_disarmed() -> None:
    with peer_team(ARDUPILOTS) as bench:
        runtime, team = bench.runtime, bench.team
        runtime.phases.set(Phase.LANDING)
        fleet = fleet_state(team.formation.positions, HOVER_THRUST)
        fleet.armed[:3] = False
        runtime.stages.phase.settle(Phase.LANDING, fleet, FLOWING)
        assert runtime.phase is Phase.LANDING
        fleet.armed[3] = False
        runtime.stages.phase.settle(Phase.LANDING, fleet, FLOWING)
        assert runtime.phase is Phase.LANDED


def test_the_lift_ends_once_the_ramp_ended_and_the_team_is_there() -> None:
    with peer_team(ARDUPILOTS) as bench:
        runtime, team = bench.runtime, bench.team
        stage = runtime.stages.phase
        runtime.phases.set(Phase.LIFTING)
        low = fleet_state(team.formation.positions, HOVER_THRUST, altitude=1.0)
        there = fleet_state(team.formation.positions, HOVER_THRUST, altitude=2.0)
        stage.advance(Phase.LIFTING, _at(2.0, 2.0), 1.0, low)  # the team is not there
        assert runtime.phase is Phase.LIFTING
        stage.advance(Phase.LIFTING, _at(1.9, 2.0), 1.25, there)  # the ramp goes on
        assert runtime.phase is Phase.LIFTING
        stage.advance(Phase.LIFTING, _at(2.0, 2.0), 1.5, there)
        assert runtime.phase is Phase.FORMATION


def test_the_aborts_hold_ends_in_a_landing() -> None:
    with peer_team(ARDUPILOTS) as bench:
        runtime, team = bench.runtime, bench.team
        runtime.phases.set(Phase.FORMATION)
        runtime.actions.abort()
        start = runtime.phases.abort_at
        assert runtime.phase is Phase.ABORTING and start is not None
        fleet = fleet_state(team.formation.positions, HOVER_THRUST)
        hold = team.config.flight.abort_hold
        runtime.stages.phase.advance(Phase.ABORTING, _at(2.0, 2.0), start + hold - 0.01, fleet)
        assert runtime.phase is Phase.ABORTING
        runtime.stages.phase.advance(Phase.ABORTING, _at(2.0, 2.0), start + hold, fleet)
        assert runtime.phase is Phase.LANDING and runtime.phases.abort_at is None
        assert np.isfinite(start)
