"""The guidance over a slow link: predicting one round trip further keeps the paper's team in
shape (gcs.loop._demand_stage follows the links' round trip; here the closed loop that says why).

Planar double integrators under eq. udi at 4 Hz with a zero-order hold, as in
tests/support/double_integrator.py, but the positions are read half a round trip late
and the setpoints act half a round trip late, as over a radio.
"""

from __future__ import annotations

import numpy as np
import pytest

from gcs.config import load_team
from gcs.guidance import Guidance, MotionDemand
from gcs.loop import LINK_DELAY_CAP_S

TEAM = load_team("configs/bebop_square.yaml")


def worst_late_error(round_trip: float, extra_lead: float, seconds: float = 60.0) -> float:
    """Worst distance error over the second half of a flight from 10 % out of shape."""
    g = Guidance.from_team(TEAM)
    g.lead = 0.5 * g.period + extra_lead
    dt = 0.005
    p, v = TEAM.formation.positions * 1.1, np.zeros((4, 2))
    past: list[tuple[np.ndarray, np.ndarray]] = []
    pending: list[tuple[float, np.ndarray]] = []
    u = np.zeros((4, 2))
    worst, next_tick = [], 0.0
    for k in range(round(seconds / dt)):
        t = k * dt
        past.append((p.copy(), v.copy()))
        if t >= next_tick - 1e-9:
            pm, vm = past[max(0, k - round(0.5 * round_trip / dt))]
            pending.append((t + 0.5 * round_trip,
                            g.accelerations(pm, vm, np.zeros(4), MotionDemand())))
            next_tick += g.period
        while pending and pending[0][0] <= t + 1e-9:
            u = pending.pop(0)[1]
        p, v = p + v * dt + 0.5 * u * dt * dt, v + u * dt
        worst.append(float(np.abs(TEAM.formation.distance_errors(p)).max()))
    return max(worst[len(worst) // 2:])


def test_without_a_link_the_half_period_lead_holds_the_shape() -> None:
    assert worst_late_error(0.0, 0.0) < 0.02


def test_a_tenth_of_a_second_each_way_needs_the_round_trip_in_the_lead() -> None:
    assert worst_late_error(0.2, 0.0) > 1.0  # the stiffest mode grows
    assert worst_late_error(0.2, 0.2) < 0.05  # predicted one round trip further: held


def test_the_cap_is_where_the_lead_stops_helping() -> None:
    """Up to the cap the lead holds the shape (decaying); a little beyond, it grows."""
    assert worst_late_error(LINK_DELAY_CAP_S, LINK_DELAY_CAP_S, seconds=120.0) < 0.05
    assert worst_late_error(0.3, 0.3, seconds=120.0) > 0.5
    beyond = 2 * LINK_DELAY_CAP_S
    assert min(worst_late_error(beyond, x) for x in (0.0, beyond / 2, beyond)) > 1.0


@pytest.mark.parametrize("round_trip", [0.05, 0.1])
def test_short_links_are_held_either_way_with_the_lead(round_trip: float) -> None:
    assert worst_late_error(round_trip, round_trip) < 0.05
