"""The geofence limits the outward motion only: a team stops at it, flies back, and is brought
back when pushed out (gcs.loop._geofence), in closed loop with the paper's guidance."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from gcs.config import load_team
from gcs.formation import fit_rotation
from gcs.guidance import Guidance, MotionDemand
from gcs.loop._geofence import RETURN_FRACTION, fence_demand

TEAM = load_team("configs/bebop_square.yaml")
SAFETY = TEAM.config.safety
GUIDANCE = Guidance.from_team(TEAM)
C1, VMAX = GUIDANCE.c1, GUIDANCE.max_speed
FENCE = SAFETY.geofence_xy


def limit(demand: MotionDemand, p: np.ndarray, v: np.ndarray,
          heading: float | None = 0.0, extra: np.ndarray | None = None) -> MotionDemand:
    points = p if extra is None else np.vstack([p, extra])
    return fence_demand(SAFETY, demand, heading=heading, points=points, velocity=v.mean(axis=0),
                        altitude=np.full(len(p), 1.5), max_speed=VMAX, c1=C1).demand


def at(x: float, y: float = 0.0) -> np.ndarray:
    return TEAM.formation.positions + np.array([x, y])


def test_far_from_the_fence_the_demand_passes_unchanged() -> None:
    d = MotionDemand(forward=0.7, right=-0.4, rotate=0.3, scale=1.1)
    assert limit(d, at(0.0), np.zeros((4, 2))) == d


def test_at_the_fence_only_the_outward_part_is_cut() -> None:
    # the outermost vehicle half the margin from the fence: where the team stops
    p = at(FENCE - 0.5 * SAFETY.geofence_margin - TEAM.formation.positions[:, 0].max())
    still = np.zeros((4, 2))
    out = limit(MotionDemand(forward=0.8, right=0.5), p, still)
    assert out.forward == pytest.approx(0.0, abs=1e-9)  # north: into the fence
    assert out.right == pytest.approx(0.5)  # east: along the fence, untouched
    back = MotionDemand(forward=-1.0)
    assert limit(back, p, still) == back  # flying back in works


def test_the_stopping_point_counts_not_only_the_position() -> None:
    """Two metres inside, but coasting north at 1 m/s: the team would stop 1/c1 further on."""
    p = at(FENCE - 2.0 - TEAM.formation.positions[:, 0].max())
    coasting = np.tile([1.0, 0.0], (4, 1))
    assert 1.0 / C1 > 2.0
    assert limit(MotionDemand(forward=1.0), p, coasting).forward < 0.0  # brake
    assert limit(MotionDemand(forward=1.0), p, np.zeros((4, 2))).forward == 1.0


def test_sticks_follow_the_team_heading() -> None:
    """Turned 90 degrees, the team's forward is east: the east fence cuts the forward stick."""
    turn = np.array([[0.0, -1.0], [1.0, 0.0]])
    p = TEAM.formation.positions @ turn.T
    heading = fit_rotation(TEAM.formation.positions, p)
    assert heading == pytest.approx(math.pi / 2)
    p = p + np.array([0.0, FENCE - 0.5 * SAFETY.geofence_margin - p[:, 1].max()])
    out = limit(MotionDemand(forward=1.0), p, np.zeros((4, 2)), heading=heading)
    assert out.forward == pytest.approx(0.0, abs=1e-9)
    assert limit(MotionDemand(right=1.0), p, np.zeros((4, 2)), heading=heading).right == 1.0


def test_outside_the_team_is_brought_back_and_the_payload_counts() -> None:
    p = at(FENCE + 0.1 - TEAM.formation.positions[:, 0].max())
    out = limit(MotionDemand(), p, np.zeros((4, 2)))
    assert out.forward == pytest.approx(-RETURN_FRACTION)
    inside = at(0.0)
    payload_out = np.array([[FENCE + 0.3, 0.0]])
    assert limit(MotionDemand(forward=1.0), inside, np.zeros((4, 2)),
                 extra=payload_out).forward < 0.0
    assert limit(MotionDemand(forward=1.0), inside, np.zeros((4, 2))).forward == 1.0


def test_a_team_that_cannot_be_placed_is_not_limited() -> None:
    d = MotionDemand(forward=1.0)
    assert limit(d, at(10.0), np.zeros((4, 2)), heading=None) == d


def fly(p: np.ndarray, v: np.ndarray, demand: MotionDemand, seconds: float,
        push: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """The point-mass team under the guidance and the fence at 4 Hz; also the farthest
    north any vehicle reached. ``push``: an acceleration the wind adds, m/s^2."""
    T = GUIDANCE.period
    reach = -np.inf
    for _ in range(round(seconds / T)):
        heading = fit_rotation(TEAM.formation.positions, p)
        u = GUIDANCE.accelerations(p, v, np.zeros(4), limit(demand, p, v, heading))
        if push is not None:
            u = u + push
        p = p + v * T + 0.5 * u * T * T
        v = v + u * T
        reach = max(reach, float(np.max(p[:, 0])))
    return p, v, reach


def test_flown_north_at_full_stick_the_team_stops_at_the_fence_then_flies_back() -> None:
    p, v, reach = fly(at(0.0), np.zeros((4, 2)), MotionDemand(forward=1.0), 40.0)
    assert reach <= FENCE, reach  # the stopping point never passes the fence
    assert p[:, 0].max() > FENCE - SAFETY.geofence_margin  # and it got there
    assert np.abs(v).max() < 0.05  # stopped
    north = p[:, 0].max()
    p, v, _ = fly(p, v, MotionDemand(forward=-1.0), 10.0)
    assert p[:, 0].max() < north - 3.0, p  # flown back south


def test_a_team_pushed_out_by_the_wind_is_brought_back() -> None:
    """A steady wind pushing north (a force: 0.05 m/s^2 on every vehicle)."""
    wind = np.array([0.05, 0.0])
    p, _, _ = fly(at(FENCE + 0.5 - TEAM.formation.positions[:, 0].max()),
                  np.zeros((4, 2)), MotionDemand(), 40.0, push=wind)
    assert p[:, 0].max() < FENCE, p[:, 0].max()


def test_the_margin_may_not_swallow_the_fence() -> None:
    with pytest.raises(ValueError, match="geofence_margin"):
        dataclasses.replace(SAFETY, geofence_margin=SAFETY.geofence_xy)
