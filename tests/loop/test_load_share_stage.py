"""The load-sharing stage (gcs.loop._load_share_stage): what each tick teaches the trims."""

from __future__ import annotations

import dataclasses

import numpy as np

from gcs.config import load_team
from gcs.loop import Phase
from gcs.loop._events import EventLog
from gcs.loop._load_share_stage import LoadShareStage
from tests.support.scripted_autopilot import HOVER_THRUST, SQUARE, fleet_state

TEAM = load_team(str(SQUARE))


def test_a_team_without_load_sharing_has_no_trims() -> None:
    off = dataclasses.replace(TEAM, config=dataclasses.replace(
        TEAM.config, flight=dataclasses.replace(TEAM.config.flight, load_sharing=False)))
    stage = LoadShareStage(off, EventLog(lambda: 0.0, None))
    assert stage.sharing is None and stage.trims is None
    stage.update(1.0, fleet_state(TEAM.formation.positions, HOVER_THRUST), Phase.FORMATION, 1.0)


def test_the_trims_move_while_carrying_and_go_back_to_zero_on_the_ground() -> None:
    stage = LoadShareStage(TEAM, EventLog(lambda: 0.0, None))
    assert stage.sharing is not None and stage.trims is not None
    high = 10.0 + TEAM.taut_altitude(1.0)
    uneven = fleet_state(TEAM.formation.positions, HOVER_THRUST, altitude=high)
    assert uneven.thrust is not None
    uneven.thrust[0] *= 1.3  # vehicle 1 carries more than its share
    now = 0.0
    for _ in range(20):
        now += 0.25
        stage.update(now, uneven, Phase.FORMATION, 1.0)
    assert np.any(stage.trims != 0.0)
    stage.update(now + 0.25, uneven, Phase.LANDED, 1.0)
    assert np.all(stage.trims == 0.0)


def test_a_silent_thrust_holds_the_trims_and_is_said_once_naming_the_vehicle() -> None:
    events = EventLog(lambda: 0.0, None)
    stage = LoadShareStage(TEAM, events)
    high = 10.0 + TEAM.taut_altitude(1.0)
    silent = fleet_state(TEAM.formation.positions, HOVER_THRUST, altitude=high)
    assert silent.thrust_age is not None
    silent.thrust_age[1] = np.inf
    for k in range(8):
        stage.update(0.25 * k, silent, Phase.FORMATION, 1.0)
    assert [e.text for e in events.recent()] == [
        "load sharing held: no collective thrust (ATTITUDE_TARGET) from vehicle(s) 2"]
    assert stage.trims is not None and np.all(stage.trims == 0.0)
