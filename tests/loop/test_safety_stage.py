"""The safety stage (gcs.loop._safety_stage) on a real loop over scripted ArduPilot links:
the tick's verdict, each rule said once while it holds, the safe radius of the acceleration
commanded, and a vehicle coming down landing the team."""

from __future__ import annotations

import numpy as np

from gcs.loop import Phase
from tests.support.scripted_autopilot import HOVER_THRUST, fleet_state, peer_team

ARDUPILOTS = {vid: ("ardupilot", {}) for vid in (1, 2, 3, 4)}


def test_before_the_team_is_ready_the_motion_is_frozen_and_nothing_is_said() -> None:
    with peer_team(ARDUPILOTS) as bench:
        safety, team = bench.runtime.stages.safety, bench.team
        verdict = safety.judge(1.0, Phase.CONNECT,
                               fleet_state(team.formation.positions, HOVER_THRUST), commanded=0.0)
        assert verdict.freeze and not verdict.land and not bench.runtime.events()


def test_a_stale_vehicle_is_said_once_while_it_lasts_and_again_when_it_recurs() -> None:
    with peer_team(ARDUPILOTS) as bench:
        runtime, team = bench.runtime, bench.team
        stale = fleet_state(team.formation.positions, HOVER_THRUST)
        stale.age[2] = team.config.safety.stale_after + 0.1
        fresh = fleet_state(team.formation.positions, HOVER_THRUST)
        verdicts = [runtime.stages.safety.judge(0.25 * k, Phase.FORMATION, f, commanded=0.0)
                    for k, f in enumerate((stale,) * 4 + (fresh,) + (stale,) * 2)]
        assert [v.freeze for v in verdicts] == [True] * 4 + [False] + [True] * 2
        said = [e.text for e in runtime.events() if "vehicle 3" in e.text]
        assert len(said) == 2 and all("motion frozen" in t for t in said), said


def test_the_safe_radius_shrinks_with_the_acceleration_commanded_above_its_floor() -> None:
    with peer_team(ARDUPILOTS) as bench:
        safety, limit = bench.runtime.stages.safety, bench.team.config.limits.accel_norm
        floor = safety.safe_radius_for(0.25 * limit)
        assert safety.safe_radius_for(0.0) == floor
        assert safety.safe_radius_for(limit) < floor
        assert np.isclose(2 * safety.safe_radius_for(limit), safety.analysis.safe_span,
                          rtol=0.05)


def test_a_vehicle_coming_down_on_its_own_lands_the_team() -> None:
    with peer_team(ARDUPILOTS) as bench:
        runtime, team = bench.runtime, bench.team
        landing = fleet_state(team.formation.positions, HOVER_THRUST,
                              modes=("GUIDED", "LAND", "GUIDED", "GUIDED"))
        verdict = runtime.stages.safety.judge(1.0, Phase.FORMATION, landing, commanded=0.0)
        assert verdict.land and verdict.freeze
        assert any("vehicle 2: coming down on its own (LAND)" in e.text
                   for e in runtime.events())
