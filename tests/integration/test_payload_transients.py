"""The team keeps its shape while the rope's pull changes: picking up, setting down, spinning.

When the ropes take up the payload's weight each vehicle is pulled towards the
payload by a force that grows from nothing to about half its own weight; the
autopilot's acceleration loop follows a growing force only with its lag, so the
faster the tension grows the further the team is pulled in (at the lift rate of
0.1 m/s the square's shape shrank by 0.24 m, beyond its safe deformation of
0.17 m). The lift therefore crosses the band where the ropes take the weight at
``flight.pickup_rate``, and the set-down crosses it again at that rate.
While the team spins, the pull turns with it and the same lag leaves each
vehicle short against the turn; the setpoints lead it by ``guidance.rope_lag``
(gcs/guidance/_rope_lead.py). Lockstep on the simulator's clock: each flight is
the same whatever the load.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from gcs.analysis import analyze
from gcs.config import Team, load_team
from gcs.guidance import Guidance, MotionDemand, rope_growth_lead, rope_pull_ned, rope_turn_lead
from gcs.testing import SimTeam
from tests.support.paths import SQUARE


def _lift_and_set_down(team: Team) -> dict[str, float]:
    with SimTeam(team, seed=2) as flight:
        flight.arm()
        flight.takeoff()
        flight.lift()
        flight.wait(2)
        assert flight.state().payload_p_ned[2] < -0.9  # lifted 1 m
        flight.set_down()
        flight.wait_for("hover")
        return dict(flight.metrics().worst_distance_error_by_phase_m)


def _with(team: Team, part: str, **changes: object) -> Team:
    config = dataclasses.replace(
        team.config, **{part: dataclasses.replace(getattr(team.config, part), **changes)})
    return dataclasses.replace(team, config=config)


def _turn_rate(p_ned: np.ndarray, v_ned: np.ndarray) -> float:
    """The team's rate of turn about its centroid, rad/s, clockwise seen from above."""
    rel = p_ned[:, :2] - p_ned[:, :2].mean(axis=0)
    vel = v_ned[:, :2] - v_ned[:, :2].mean(axis=0)
    return float(np.sum(rel[:, 0] * vel[:, 1] - rel[:, 1] * vel[:, 0]) / np.sum(rel**2))


def _spin(team: Team) -> tuple[float, float]:
    """Worst distance error of a 10 s spin at full stick and the 3 s after it, the payload
    carried, and the team's rate of turn at the spin's end (rad/s, clockwise seen from
    above)."""
    with SimTeam(team, seed=2) as flight:
        flight.arm()
        flight.takeoff()
        flight.lift()
        flight.wait(2)
        flight.sticks(rotate=1.0, seconds=10)
        state = flight.state()
        rate = _turn_rate(state.p_ned, state.v_ned)
        flight.wait(3)
        return flight.metrics().worst_distance_error_by_phase_m["formation"], rate


@pytest.fixture(scope="module")
def square() -> Team:
    return load_team(SQUARE)


def test_the_square_picks_up_and_sets_down_within_its_safe_deformation(square: Team) -> None:
    safe = analyze(square).safe_deformation
    errors = _lift_and_set_down(square)
    # seed 2: 0.12 m lifting and 0.13 m setting down, of 0.17 m (0.24 m at the lift rate)
    assert errors["lifting"] < 0.85 * safe, errors
    assert errors["setting down"] < 0.85 * safe, errors


def test_lifting_at_the_full_lift_rate_pulls_the_shape_beyond_it(square: Team) -> None:
    """The same flight with no slow band: what the band prevents."""
    fast = _with(square, "flight", pickup_rate=square.config.flight.lift_rate)
    errors = _lift_and_set_down(fast)
    assert errors["lifting"] > analyze(square).safe_deformation, errors


def test_the_lead_cancels_a_lag_behind_a_growing_pull() -> None:
    """While the ropes take the payload, each pull grows as ``f F``: an acceleration loop
    ``lag`` late gives ``lag df/dt F / m`` more than commanded (inward); the lead is minus
    that, outward; nothing while the share carried holds still."""
    pull = np.array([[-0.9, 0.0], [0.28, 0.86]])  # N, NED: the rope pulls toward the payload
    rate, lag, mass = 0.5, 0.15, 0.5
    late = (rate * 2.0 - rate * (2.0 - lag)) * pull / mass  # f(t) F - f(t - lag) F, over m
    assert np.allclose(rope_growth_lead(pull, rate, lag, mass), -late)
    assert rope_growth_lead(pull, rate, lag, mass)[0, 0] > 0.0  # pulled south: led north
    assert not rope_growth_lead(pull, 0.0, lag, mass).any()


def test_the_lead_cancels_a_lag_behind_a_turning_pull() -> None:
    """An acceleration loop that follows the pull ``lag`` late gives the vehicle
    ``(F(t) - F(t - lag)) / m`` more than commanded; the lead is minus that, to first
    order in ``omega lag``."""
    pull = np.array([[-0.8, 0.1], [0.3, 0.6]])  # N, NED
    omega, lag, mass = 0.4, 0.15, 0.4
    a = omega * lag
    late = rope_pull_ned(pull, -a)  # the same pulls, turned back by omega lag
    extra = (pull - late) / mass
    lead = rope_turn_lead(pull, omega, lag, mass)
    assert np.allclose(lead, -extra, atol=0.5 * a**2 * 0.81 / mass)
    # clockwise seen from above (the guidance's positive rotate): the vehicle north of
    # the payload (pulled south) moves east, and the lead pushes it on east
    assert rope_turn_lead(np.array([[-1.0, 0.0]]), 1.0, 1.0, 1.0)[0] == pytest.approx([0, 1])
    assert rope_pull_ned(np.array([[1.0, 0.0]]), math.pi / 2)[0] == pytest.approx([0, 1])
    square = load_team(SQUARE)
    assert Guidance.from_team(square).angular_rate(MotionDemand(rotate=1.0)) > 0
    north_east = np.array([[1.0, 0.0], [0.0, 0.0]]), np.array([[0.0, 1.0], [0.0, 0.0]])
    assert _turn_rate(*north_east) > 0  # the one at north moving east: clockwise


def test_the_spin_turns_as_commanded_and_keeps_the_shape_with_the_rope_lead(
        square: Team) -> None:
    """Without the rope lead the lag brakes the turn (about 0.1 rad/s of the 0.4
    commanded); with it the team turns at the commanded rate, clockwise. Without the turn
    compensation (eq. udi alone) the centripetal feed-forward of the commanded turn pulls
    the shape in while the team speeds up, and widens it when the spin stops."""
    assert square.config.guidance.rope_lag == 0.15
    assert square.config.guidance.turn_compensation
    commanded = Guidance.from_team(square).angular_rate(MotionDemand(rotate=1.0))
    (led, led_rate), (_, unled_rate), (plain, plain_rate) = (
        _spin(square), _spin(_with(square, "guidance", rope_lag=0.0)),
        _spin(_with(square, "guidance", turn_compensation=False)))
    assert unled_rate < 0.5 * commanded, unled_rate
    assert led_rate == pytest.approx(commanded, rel=0.15), (led_rate, commanded)
    assert plain_rate == pytest.approx(commanded, rel=0.15), (plain_rate, commanded)
    assert led < 0.5 * plain, (led, plain)  # 10 s spin: 0.05 against 0.13 m


def test_the_team_takes_off_below_its_shortest_rope(square: Team) -> None:
    """With ropes of their own lengths the first to go taut is the shortest: the take-off
    stops ``flight.takeoff_slack`` below it, with every rope still slack."""
    ropes = (1.0, 1.118, 1.118, 1.118)
    uneven = _with(square, "payload", rope_lengths=ropes, rope_length=max(ropes),
                   mass=0.1)  # analysis passes
    first = math.sqrt(1.0 - 0.5)  # 1 m rope, 0.707 m from the centroid
    assert uneven.taut_altitude() == pytest.approx(first, abs=1e-3)
    assert square.taut_altitude() == pytest.approx(math.sqrt(1.25 - 0.5))
    with SimTeam(uneven, seed=1) as flight:
        flight.arm()
        flight.takeoff()
        flight.wait(2)
        state = flight.state()
        assert float(np.mean(-state.p_ned[:, 2])) == pytest.approx(
            first - uneven.config.flight.takeoff_slack, abs=0.1)
        tension = state.rope_tension
        assert tension is not None and float(tension.max()) == 0.0
