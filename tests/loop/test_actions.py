"""The phase actions (gcs.loop._actions) on a real loop over scripted ArduPilot links."""

from __future__ import annotations

import pytest

from gcs.loop import Action, Phase, PhaseError
from tests.support.scripted_autopilot import peer_team

ARDUPILOTS = {vid: ("ardupilot", {}) for vid in (1, 2, 3, 4)}


def test_an_action_the_phase_does_not_allow_is_refused_naming_the_phase() -> None:
    with peer_team(ARDUPILOTS) as bench:
        with pytest.raises(PhaseError, match="cannot take off while connect"):
            bench.runtime.actions.request(Action.TAKEOFF)
        assert not bench.runtime.actions.running


def test_the_lift_sets_its_altitude_before_the_phase_moves() -> None:
    with peer_team(ARDUPILOTS) as bench:
        runtime, team = bench.runtime, bench.team
        runtime.phases.set(Phase.HOVER)
        runtime.actions.request(Action.LIFT)
        assert runtime.phase is Phase.LIFTING
        target = runtime.operator.snapshot(runtime.clock.now()).altitude_target
        assert target == pytest.approx(team.taut_altitude(1.0) + team.config.flight.lift_height)
        runtime.actions.request(Action.SET_DOWN)
        target = runtime.operator.snapshot(runtime.clock.now()).altitude_target
        assert target == pytest.approx(team.taut_altitude(1.0)
                                       - team.config.flight.takeoff_slack)


def test_an_abort_centres_the_sticks_and_a_second_one_changes_nothing() -> None:
    with peer_team(ARDUPILOTS) as bench:
        runtime = bench.runtime
        runtime.phases.set(Phase.FORMATION)
        runtime.operator.set_sticks(0.5, 0.0, 0.0, now=runtime.clock.now(), source="test")
        runtime.actions.request(Action.ABORT)
        runtime.actions.request(Action.ABORT)
        assert runtime.phase is Phase.ABORTING
        assert runtime.operator.snapshot(runtime.clock.now()).demand.forward == 0.0
        assert [e.text for e in runtime.events()].count("phase: aborting") == 1

