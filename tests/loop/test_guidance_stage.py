"""The guidance stage (gcs.loop._guidance_stage): finite, saturated accelerations; a held
team pulled back to its own points; nothing where the team cannot be placed."""

from __future__ import annotations

import numpy as np

from gcs.common import HOLD_KP, HOLD_KV
from gcs.config import load_team
from gcs.guidance import Guidance, MotionDemand
from gcs.loop import FleetState
from gcs.loop._events import EventLog
from gcs.loop._guidance_stage import GuidanceStage
from gcs.loop._load_share_stage import load_sharing
from gcs.loop._rope_lead_stage import RopeLead
from tests.support.scripted_autopilot import HOVER_THRUST, SQUARE, fleet_state

TEAM = load_team(str(SQUARE))


def _stage() -> GuidanceStage:
    guidance = Guidance.from_team(TEAM)
    events = EventLog(lambda: 0.0, None)
    return GuidanceStage(TEAM, guidance, RopeLead(TEAM, guidance, load_sharing(TEAM), events))


def _fleet(offset: float = 0.0) -> FleetState:
    return fleet_state(TEAM.formation.positions + offset, HOVER_THRUST)


def test_a_team_in_shape_at_rest_gets_nothing_and_a_push_moves_every_vehicle() -> None:
    stage = _stage()
    still = stage.accelerations(_fleet(), MotionDemand(), hold=False, hold_points=None,
                                carrying=False)
    assert np.allclose(still, 0.0, atol=1e-9) and stage.largest < 1e-9
    push = stage.accelerations(_fleet(), MotionDemand(forward=1.0), hold=False,
                               hold_points=None, carrying=False)
    assert np.all(push[:, 0] > 0.1) and stage.largest == np.max(np.linalg.norm(push, axis=1))
    lim = TEAM.config.limits
    assert np.all(np.linalg.norm(push, axis=1) <= lim.accel_norm + 1e-12)
    assert np.all(np.abs(push) <= lim.accel_axis + 1e-12)


def test_a_held_vehicle_is_pulled_back_to_its_own_point_whatever_the_others_do() -> None:
    stage = _stage()
    fleet = fleet_state(TEAM.formation.positions, HOVER_THRUST)
    points = TEAM.formation.positions.copy()
    fleet.p_ned[0, 0] += 0.1  # vehicle 1 drifted 0.1 m north
    fleet.v_ned[2, 1] = 0.2  # vehicle 3 moves east
    accel = stage.accelerations(fleet, MotionDemand(forward=1.0), hold=True,
                                hold_points=points, carrying=False)
    assert np.allclose(accel[0], [-HOLD_KP * 0.1, 0.0])
    assert np.allclose(accel[2], [0.0, -HOLD_KV * 0.2])
    assert np.allclose(accel[[1, 3]], 0.0)  # no command depends on another's position
    damped = stage.accelerations(fleet, MotionDemand(), hold=True, hold_points=None,
                                 carrying=False)
    assert np.allclose(damped[2], [0.0, -stage.guidance.c1 * 0.2]) and damped[0, 0] == 0.0


def test_nothing_moves_a_team_that_cannot_be_placed_or_is_not_streamed_to() -> None:
    stage = _stage()
    lost = fleet_state(TEAM.formation.positions, HOVER_THRUST)
    lost.p_ned[1] = np.nan
    lost.v_ned[1] = np.nan
    assert not lost.located
    accel = stage.accelerations(lost, MotionDemand(forward=1.0), hold=False, hold_points=None,
                                carrying=False)
    assert np.all(accel == 0.0) and stage.largest == 0.0
    held = stage.accelerations(lost, MotionDemand(), hold=True,
                               hold_points=TEAM.formation.positions, carrying=False)
    assert np.all(np.isfinite(held))  # NaN telemetry damps nothing, never a NaN setpoint
    stage.largest = 1.0
    assert np.all(stage.idle(4) == 0.0) and stage.idle(4).shape == (4, 2)
    assert stage.largest == 0.0
