"""INDI control of the paper's section IV: its pieces, and tracking with real physics."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.signal import freqz, lfilter

from sim.config import load_world_config
from sim.dynamics import physics_step
from sim.layout import Layout, paper_square
from sim.scenario import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    build_team,
    take_off,
)
from sim.world import World
from vehicles.airframe import load_airframe
from vehicles.autopilot import Autopilot
from vehicles.butterworth import biquad_reset, biquad_step, butterworth2
from vehicles.config import load_autopilot_config
from vehicles.indi import acceleration_increment, g_matrix
from vehicles.modes import Mode
from vehicles.quaternion import euler_to_quat, quat_to_euler, quat_to_rotation
from vehicles.rotors import effectiveness_matrix

RNG = np.random.default_rng(2019)


def thrust_vector(phi: float, theta: float, psi: float, thrust_z: float) -> np.ndarray:
    """T R(eta) e_z: the thrust along +z_body expressed in NED."""
    r = np.array(quat_to_rotation(*euler_to_quat(phi, theta, psi))).reshape(3, 3)
    return thrust_z * r[:, 2]


@pytest.mark.parametrize("sample", range(5))
def test_g_matrix_is_the_jacobian_of_the_thrust_vector(sample: int) -> None:
    phi, theta = RNG.uniform(-0.4, 0.4, 2)
    psi = RNG.uniform(-math.pi, math.pi)
    t = -RNG.uniform(2.0, 7.0)
    h = 1e-6
    numeric = np.column_stack([
        (thrust_vector(phi + h, theta, psi, t) - thrust_vector(phi - h, theta, psi, t)) / (2 * h),
        (thrust_vector(phi, theta + h, psi, t) - thrust_vector(phi, theta - h, psi, t)) / (2 * h),
        (thrust_vector(phi, theta, psi, t + h) - thrust_vector(phi, theta, psi, t - h)) / (2 * h),
    ])
    assert np.array(g_matrix(phi, theta, psi, t)).reshape(3, 3) == pytest.approx(numeric, abs=1e-6)


def test_acceleration_increment_inverts_g() -> None:
    for _ in range(20):
        phi, theta, psi = RNG.uniform(-0.4, 0.4), RNG.uniform(-0.4, 0.4), RNG.uniform(-3, 3)
        t, m = -RNG.uniform(2.0, 7.0), 0.4
        e = RNG.normal(size=3)
        du = np.array(acceleration_increment(phi, theta, psi, t, m, *e))
        g = np.array(g_matrix(phi, theta, psi, t)).reshape(3, 3)
        assert g @ du / m == pytest.approx(e, abs=1e-9)


def test_controller_effectiveness_matches_the_simulated_rotor_wrench() -> None:
    airframe = load_airframe(DEFAULT_AIRFRAME)
    world = World(airframe=airframe, config=load_world_config(DEFAULT_WORLD_CONFIG),
                  p0_ned=np.array([[0.0, 0.0, -50.0]]), rope_length=np.array([100.0]),
                  payload_mass=0.1, payload_p0_ned=np.array([0.0, 0.0, -49.0]),
                  rng=np.random.default_rng(0))
    speeds = np.array([[600.0, 700.0, 820.0, 540.0]])
    world.state.rotor_speed[:] = speeds
    physics_step(world.state, world.params, speeds, np.zeros(3))
    thrusts = airframe.thrust_coefficient * speeds[0] ** 2
    torque = np.array(airframe.inertia) * world.state.omega_body[0] / world.params.dt
    wrench = effectiveness_matrix(airframe) @ thrusts
    assert torque == pytest.approx(wrench[:3], rel=1e-9)
    assert -world.state.specific_force_body[0, 2] * airframe.mass == pytest.approx(wrench[3])


def test_butterworth_has_unit_dc_gain_and_half_power_at_the_cutoff() -> None:
    coef = butterworth2(5.0, 512.0)
    b, a = coef[:3], np.array([1.0, coef[3], coef[4]])
    _, h = freqz(b, a, worN=[0.0, 5.0, 50.0], fs=512.0)
    assert abs(h[0]) == pytest.approx(1.0)
    assert abs(h[1]) == pytest.approx(1.0 / math.sqrt(2.0), rel=1e-6)
    assert abs(h[2]) < 0.011  # -40 dB/decade
    # The kernel's biquad reproduces scipy's filter, and a reset is a steady state.
    x = RNG.normal(size=200)
    z = np.zeros((1, 1, 2))
    ours = [biquad_step(coef, z, 0, 0, xi) for xi in x]
    assert ours == pytest.approx(lfilter(b, a, x), abs=1e-12)
    biquad_reset(coef, z, 0, 0, 3.5)
    assert [biquad_step(coef, z, 0, 0, 3.5) for _ in range(5)] == pytest.approx([3.5] * 5)
    with pytest.raises(ValueError, match="Nyquist"):
        butterworth2(300.0, 512.0)


def true_accel_ned(world: World) -> np.ndarray:
    """Noise-free acceleration of every vehicle, NED, from the physics."""
    out = np.empty((world.n_vehicles, 3))
    for i in range(world.n_vehicles):
        r = np.array(quat_to_rotation(*world.state.q_wxyz[i])).reshape(3, 3)
        out[i] = r @ world.state.specific_force_body[i] + [0.0, 0.0, world.config.gravity]
    return out


@pytest.fixture(scope="module")
def step_response() -> np.ndarray:
    """The paper's team, payload hanging, autopilots believing the rotors 20 % stronger
    than they are; all four commanded a 1 m/s^2 north step at t = 1 s (altitude held).

    Drag is switched off so the acceleration stays a true steady state: with drag
    the force grows with speed and INDI trails that ramp by about 0.02 m/s^2.
    Returns the true north acceleration (samples at 512 Hz, 4 vehicles).
    """
    airframe = dataclasses.replace(load_airframe(DEFAULT_AIRFRAME), drag_coefficient=0.0)
    believed = dataclasses.replace(airframe,
                                   thrust_coefficient=1.2 * airframe.thrust_coefficient)
    config = dataclasses.replace(load_world_config(DEFAULT_WORLD_CONFIG),
                                 payload_drag_coefficient=0.0)
    world, autopilot = build_team(paper_square(), payload_mass=0.4,
                                  rng=np.random.default_rng(21), airframe=airframe,
                                  world_config=config,
                                  autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG),
                                  autopilot_airframe=believed)
    take_off(world, autopilot, 1.5)
    world.run(autopilot, 3.0)
    z_hold = autopilot.state.p_hold[:, 2].copy()
    period = 1.0 / autopilot.rate_hz
    accel = []
    for k in range(4 * 512):
        command = 1.0 if k >= 512 else 0.0
        for i in range(4):
            autopilot.set_accel_xy_pos_z_setpoint(i, (command, 0.0), z_hold[i])
            if k == 0:
                assert autopilot.start_offboard(i).accepted
        world.run(autopilot, period)
        accel.append(true_accel_ned(world)[:, 0])
    assert all(m == Mode.OFFBOARD for m in autopilot.modes)
    return np.array(accel)


def test_acceleration_step_is_tracked_within_a_fraction_of_a_second(
        step_response: np.ndarray) -> None:
    team_mean = step_response.mean(axis=1)
    before = team_mean[:512]
    assert np.abs(before.mean()) < 0.02
    after = team_mean[512:]
    time_constant = np.argmax(after >= 1.0 - math.exp(-1.0)) / 512.0
    assert 0.02 < time_constant < 0.25, time_constant  # measured 0.13 s


def test_acceleration_step_has_no_steady_state_error_despite_rope_and_model_error(
        step_response: np.ndarray) -> None:
    # 1 to 3 s after the step: each vehicle's mean acceleration is the command.
    # Without INDI's increments the rope's 0.8 N horizontal pull alone would
    # leave 2 m/s^2 of error, and the 20 % thrust error a fifth of the command.
    # (Sensor noise moves a vehicle's 2 s mean by about 0.01 m/s^2.)
    steady = step_response[2 * 512:].mean(axis=0)
    assert steady == pytest.approx(np.ones(4), abs=0.03)
    assert steady.mean() == pytest.approx(1.0, abs=0.01)


def test_bank_limit_holds_when_more_acceleration_is_asked() -> None:
    # One vehicle on a rope too long to ever pull: 5 m/s^2 needs 27 degrees.
    layout = Layout(np.zeros((1, 3)), np.array([20.0]), np.array([0.0, 3.0, 0.0]))
    world, autopilot = build_team(layout, payload_mass=0.4, rng=np.random.default_rng(4),
                                  airframe=load_airframe(DEFAULT_AIRFRAME),
                                  world_config=load_world_config(DEFAULT_WORLD_CONFIG),
                                  autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    take_off(world, autopilot, 1.5)
    bank = math.radians(autopilot.config.bank_max_deg)
    for accel_xy in ((5.0, 0.0), (0.0, -5.0), (4.0, 4.0)):
        roll_pitch = []
        for _ in range(256):  # 0.5 s at 512 Hz
            autopilot.set_accel_xy_pos_z_setpoint(0, accel_xy, -1.5)
            if autopilot.mode(0) != Mode.OFFBOARD:
                assert autopilot.start_offboard(0).accepted
            world.run(autopilot, 1.0 / 512.0)
            roll_pitch.append(quat_to_euler(*world.state.q_wxyz[0])[:2])
        peak = np.abs(np.array(roll_pitch)).max(axis=0)
        for axis in range(2):
            if accel_xy[1 - axis] != 0.0:  # roll serves east, pitch serves north
                assert bank - math.radians(0.5) < peak[axis] < bank + math.radians(0.5), peak
        assert np.all(world.rope_tension == 0.0)
        assert autopilot.hold(0).accepted
        world.run(autopilot, 3.0)


def test_autopilot_refuses_a_setpoint_it_cannot_use() -> None:
    autopilot = Autopilot(load_airframe(DEFAULT_AIRFRAME),
                          load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG), 2)
    with pytest.raises(ValueError, match="accel_ned"):
        autopilot.set_accel_setpoint(0, (1.0, 2.0))
    with pytest.raises(ValueError, match="accel_xy_ned"):
        autopilot.set_accel_xy_pos_z_setpoint(0, (math.nan, 0.0), -1.0)
    with pytest.raises(ValueError, match="z_ned"):
        autopilot.set_accel_xy_pos_z_setpoint(0, (0.0, 0.0), math.inf)
    with pytest.raises(IndexError):
        autopilot.set_accel_setpoint(2, (0.0, 0.0, 0.0))
