"""Ropes pull only when taut and never push, in the kernel and in flight."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gcs.wire import SimMode
from sim import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    build_team,
    load_world_config,
    paper_square,
    take_off,
)
from sim._ropes import rope_tension
from vehicles import load_airframe, load_autopilot_config, quat_to_rotation

K, C, L = 5000.0, 30.0, 1.0


def test_taut_rope_is_a_spring_damper_along_the_rope() -> None:
    tension, ux, uy, uz = rope_tension(0.0, 0.6, -0.801, 0.0, 0.0, -0.1, L, K, C)
    dist = math.hypot(0.6, 0.801)
    rate = -0.1 * (-0.801 / dist)
    assert tension == pytest.approx(K * (dist - L) + C * rate)
    assert (ux, uy, uz) == pytest.approx((0.0, 0.6 / dist, -0.801 / dist))


@pytest.mark.parametrize("d, dv", [
    ((0.0, 0.0, -0.99), (0.0, 0.0, 0.0)),  # shorter than the rope: slack
    ((0.0, 0.0, -0.5), (0.0, 0.0, 3.0)),  # slack and closing fast
    ((0.3, 0.0, 0.0), (-5.0, 0.0, 0.0)),  # slack, sideways
    ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),  # ends at the same point
])
def test_slack_rope_has_no_tension(d: tuple[float, float, float],
                                   dv: tuple[float, float, float]) -> None:
    assert rope_tension(*d, *dv, L, K, C) == (0.0, 0.0, 0.0, 0.0)


def test_stretched_rope_closing_fast_pulls_nothing_rather_than_pushing() -> None:
    # 1 mm stretch (5 N of spring) but closing at 1 m/s (-30 N of damping).
    tension, *_ = rope_tension(0.0, 0.0, -1.001, 0.0, 0.0, 1.0, L, K, C)
    assert tension == 0.0


@pytest.fixture(scope="module")
def one_rope_slack() -> dict[str, np.ndarray]:
    """The paper's team hovering; vehicle 0 then flies 0.3 m in towards the centre.

    The test plays the GCS for vehicle 0: a position PD on its telemetry gives
    x/y acceleration setpoints at 16 Hz, altitude held by the vehicle.
    """
    airframe = load_airframe(DEFAULT_AIRFRAME)
    world, autopilot = build_team(
        paper_square(), payload_mass=0.4, rng=np.random.default_rng(5), airframe=airframe,
        world_config=load_world_config(DEFAULT_WORLD_CONFIG),
        autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    take_off(world, autopilot, 1.5)
    world.run(autopilot, 3.0)
    taut_before = world.rope_tension
    hold = autopilot.state.p_hold[0].copy()
    target_xy = hold[:2] * (1.0 - 0.3 / np.linalg.norm(hold[:2]))

    def send() -> None:
        p, v = autopilot.p_ned[0], autopilot.v_ned[0]
        autopilot.set_accel_xy_pos_z_setpoint(0, 1.5 * (target_xy - p[:2]) - 2.2 * v[:2],
                                              hold[2])

    send()
    assert autopilot.start_offboard(0).accepted
    tensions, tilts, lifts, distances = [], [], [], []
    for k in range(8 * 16):  # 8 s at 16 Hz; the last 3 s are checked
        send()
        world.run(autopilot, 1.0 / 16.0)
        if k < 5 * 16:
            continue
        tension = world.rope_tension
        to_vehicle = world.p_ned - world.payload_p_ned
        dist = np.linalg.norm(to_vehicle, axis=1)
        thrust_axis = -np.array(quat_to_rotation(*world.state.q_wxyz[0])).reshape(3, 3)[:, 2]
        tensions.append(tension)
        tilts.append(math.acos(-thrust_axis[2]))
        lifts.append(np.sum(tension * -to_vehicle[:, 2] / dist))
        distances.append(dist)
    assert autopilot.mode(0) == SimMode.OFFBOARD
    return {"taut_before": taut_before, "tension": np.array(tensions), "tilt": np.array(tilts),
            "lift": np.array(lifts), "distance": np.array(distances),
            "rope": world.params.rope_length}


def test_a_slack_rope_in_flight_pulls_and_pushes_nothing(
        one_rope_slack: dict[str, np.ndarray]) -> None:
    r = one_rope_slack
    assert np.all(r["taut_before"] > 0.5)
    assert np.all(r["distance"][:, 0] < r["rope"][0] - 0.1)
    assert np.all(r["tension"][:, 0] == 0.0)
    # No rope force at all on vehicle 0: it hovers upright (noise jitter only).
    assert np.mean(r["tilt"]) < math.radians(1.0)


def test_the_taut_ropes_carry_the_whole_payload(one_rope_slack: dict[str, np.ndarray]) -> None:
    r = one_rope_slack
    assert np.all(r["tension"][:, 1:] > 0.0)
    assert np.mean(r["lift"]) == pytest.approx(0.4 * 9.81, rel=0.02)
