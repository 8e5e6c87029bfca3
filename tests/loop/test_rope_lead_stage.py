"""The ropes' lead (gcs.loop._rope_lead_stage): nothing without a lag or a change to lead;
a spinning team's lead turns each vehicle along its path about the centroid."""

from __future__ import annotations

import dataclasses

import numpy as np

from gcs.config import load_team
from gcs.guidance import Guidance, MotionDemand
from gcs.loop._events import EventLog
from gcs.loop._load_share_stage import load_sharing
from gcs.loop._rope_lead_stage import RopeLead
from tests.support.scripted_autopilot import HOVER_THRUST, SQUARE, fleet_state

TEAM = load_team(str(SQUARE))
SPIN = MotionDemand(rotate=1.0)


def _lead(team: object = TEAM) -> RopeLead:
    guidance = Guidance.from_team(TEAM)
    return RopeLead(TEAM if team is TEAM else team, guidance,  # type: ignore[arg-type]
                    load_sharing(TEAM), EventLog(lambda: 0.0, None))


def test_nothing_is_led_without_a_lag_or_without_a_spin_or_a_pickup() -> None:
    fleet = fleet_state(TEAM.formation.positions, HOVER_THRUST)
    accel = np.full((4, 2), 0.1)
    no_lag = dataclasses.replace(TEAM, config=dataclasses.replace(
        TEAM.config, guidance=dataclasses.replace(TEAM.config.guidance, rope_lag=0.0)))
    assert _lead(no_lag).apply(fleet, SPIN, accel, carrying=True) is accel
    assert _lead().apply(fleet, MotionDemand(forward=1.0), accel, carrying=True) is accel
    assert _lead().apply(fleet, SPIN, accel, carrying=False) is accel  # not carrying: no spin


def test_a_carried_spin_is_led_along_each_vehicles_path_and_saturated() -> None:
    assert TEAM.config.guidance.rope_lag > 0
    fleet = fleet_state(TEAM.formation.positions, HOVER_THRUST)
    assert fleet.thrust_age is not None
    fleet.thrust_age[:] = np.inf  # thrusts unknown: the ropes are assumed to carry
    lead = _lead().apply(fleet, SPIN, np.zeros((4, 2)), carrying=True)
    assert np.all(np.linalg.norm(lead, axis=1) > 0.05)
    assert np.allclose(np.einsum("ij,ij->i", lead, TEAM.formation.positions), 0.0, atol=1e-9)
    big = _lead().apply(fleet, SPIN, np.full((4, 2), 50.0), carrying=True)
    assert np.all(np.linalg.norm(big, axis=1) <= TEAM.config.limits.accel_norm + 1e-12)
