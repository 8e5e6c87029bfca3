"""The world as a library: configs, inputs, determinism, sensors at rest, one kernel path."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from gcs.common import ConfigError
from gcs.wire import SimMode
from sim import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    build_team,
    load_world_config,
    paper_square,
    ring_layout,
    take_off,
)
from sim._config import SensorConfig, WindConfig, WorldConfig
from sim._world import World
from tests.support.worlds import aloft
from vehicles import (
    Autopilot,
    AutopilotConfig,
    load_airframe,
    load_autopilot_config,
    quat_to_rotation,
)
from vehicles._airframe import bebop2
from vehicles._quaternion import euler_to_quat, quat_multiply


def team(seed: int, config: WorldConfig | None = None) -> tuple[World, Autopilot]:
    return build_team(paper_square(), payload_mass=0.4, rng=np.random.default_rng(seed),
                      airframe=load_airframe(DEFAULT_AIRFRAME),
                      world_config=config or load_world_config(DEFAULT_WORLD_CONFIG),
                      autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))


def snapshot(world: World, autopilot: Autopilot) -> list[np.ndarray]:
    return [*world.state, *world.measurements(), *autopilot.state]


def test_shipped_config_files_state_the_defaults() -> None:
    assert load_world_config(DEFAULT_WORLD_CONFIG) == WorldConfig()
    assert load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG) == AutopilotConfig()
    assert load_airframe(DEFAULT_AIRFRAME) == bebop2()  # no defaults: every field in the file


@pytest.mark.parametrize("mapping, where, words", [
    ({"rope": {"stiffness": -1.0}}, "rope.stiffness", "greater than 0"),
    ({"sensors": {"imu_rate_hz": 500.0}}, "sensors.imu_rate_hz", "must divide physics_rate_hz"),
    ({"wind": {"gust_sdt": 1.0}}, "wind.gust_sdt", "unknown field"),
    ({"ground": {"friction_coefficient": "high"}}, "ground.friction_coefficient",
     "expected a number"),
])
def test_a_wrong_world_file_is_refused_in_one_line_naming_file_and_field(
        tmp_path: Path, mapping: dict[str, object], where: str, words: str) -> None:
    path = tmp_path / "world.yaml"
    path.write_text(yaml.safe_dump(mapping))
    with pytest.raises(ConfigError) as info:
        load_world_config(path)
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith(f"{path}: ") and where in text and words in text, text


def test_a_wrong_autopilot_file_is_refused_naming_the_field(tmp_path: Path) -> None:
    path = tmp_path / "autopilot.yaml"
    path.write_text("bank_max_deg: 95\n")
    with pytest.raises(ConfigError, match=r"autopilot\.yaml: bank_max_deg: must be less than 90"):
        load_autopilot_config(path)


def test_world_refuses_inconsistent_arrays() -> None:
    airframe, config = bebop2(), WorldConfig()
    good = {"airframe": airframe, "config": config, "p0_ned": np.zeros((2, 3)),
            "rope_length": np.ones(2), "payload_mass": 0.4, "payload_p0_ned": np.zeros(3),
            "rng": np.random.default_rng(0)}
    World(**good)
    for key, bad in (("p0_ned", np.zeros((2, 2))), ("rope_length", np.ones(3)),
                     ("rope_length", np.array([1.0, 0.0])), ("payload_mass", 0.0),
                     ("payload_p0_ned", np.zeros(2)), ("yaw0", np.zeros(3))):
        with pytest.raises(ValueError, match=key):
            World(**{**good, key: bad})
    world = World(**good)
    with pytest.raises(ValueError, match="duration"):
        world.step(np.zeros((2, 4)), 0.001)
    with pytest.raises(ValueError, match="rotor_speed_cmd"):
        world.step(np.zeros((3, 4)), 1.0 / 2048.0)
    with pytest.raises(ValueError, match="vehicles"):
        world.run(Autopilot(airframe, AutopilotConfig(), 3), 1.0 / 512.0)


def test_resting_team_reads_one_g_up_and_does_not_move() -> None:
    world, autopilot = team(seed=1)
    world.run(autopilot, 2.0)
    accel, gyro = [], []
    for _ in range(512):
        world.run(autopilot, 1.0 / 64.0)
        accel.append(world.measurements().accel_body.copy())
        gyro.append(world.measurements().gyro_body.copy())
    mean_accel = np.mean(accel, axis=0)
    # Specific force of a vehicle resting on the ground: 1 g upwards, i.e. -g on z_body
    # (512 samples of 0.3 m/s^2 noise: the mean is good to 0.013 m/s^2, one sigma).
    assert mean_accel == pytest.approx(np.tile([0.0, 0.0, -9.81], (4, 1)), abs=0.06)
    assert np.std(np.array(accel)[:, :, 2]) == pytest.approx(0.3, rel=0.1)  # configured noise
    assert np.abs(np.mean(gyro, axis=0)).max() < 0.002
    assert np.abs(world.p_ned - paper_square().p0_ned).max() < 0.002
    assert np.abs(world.payload_p_ned).max() < 0.003
    assert np.all(world.rope_tension == 0.0)


def test_runs_are_reproducible_and_do_not_depend_on_chunking() -> None:
    a_world, a_pilot = team(seed=3)
    b_world, b_pilot = team(seed=3)
    c_world, c_pilot = team(seed=4)
    for world, pilot in ((a_world, a_pilot), (b_world, b_pilot), (c_world, c_pilot)):
        take_off(world, pilot, 1.0)
    a_world.run(a_pilot, 2.0)
    for _ in range(16):
        b_world.run(b_pilot, 0.125)
    c_world.run(c_pilot, 2.0)
    assert a_world.t == b_world.t
    for a, b in zip(snapshot(a_world, a_pilot), snapshot(b_world, b_pilot), strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a_world.p_ned, c_world.p_ned)


def test_python_stepping_and_the_lockstep_kernel_fly_identically() -> None:
    """World.run fuses autopilot and physics in one compiled loop; stepping
    Autopilot.step and World.step from Python is the same computation."""
    fused_world, fused_pilot = team(seed=9)
    loop_world, loop_pilot = team(seed=9)
    for world, pilot in ((fused_world, fused_pilot), (loop_world, loop_pilot)):
        world.run(pilot, 1.0 / 32.0)
        for i in range(4):
            assert pilot.arm(i).accepted and pilot.takeoff(i, 1.0).accepted
    period = 1.0 / fused_pilot.rate_hz
    fused_world.run(fused_pilot, 3.0)
    for _ in range(round(3.0 / period)):
        loop_world.step(loop_pilot.step(loop_world.measurements()), period)
    assert fused_world.t == loop_world.t
    assert np.min(-fused_world.p_ned[:, 2]) > 0.5  # it flew
    for a, b in zip(snapshot(fused_world, fused_pilot), snapshot(loop_world, loop_pilot),
                    strict=True):
        np.testing.assert_array_equal(a, b)


def test_gusts_follow_their_statistics() -> None:
    config = dataclasses.replace(
        load_world_config(DEFAULT_WORLD_CONFIG),
        wind=dataclasses.replace(WorldConfig().wind, mean_ned=(2.0, 0.0, 0.0), gust_std=0.5,
                                 gust_time_constant=0.5),
        sensors=SensorConfig())
    world, autopilot = team(seed=2, config=config)
    take_off(world, autopilot, 1.5)
    samples = []
    for _ in range(400):
        world.run(autopilot, 0.125)
        samples.append(world.wind_ned)
    wind = np.array(samples)
    assert wind.mean(axis=0) == pytest.approx([2.0, 0.0, 0.0], abs=0.15)
    assert wind.std(axis=0) == pytest.approx([0.5, 0.5, 0.5], rel=0.25)


def test_steady_wind_deflects_the_hanging_payload_by_its_drag() -> None:
    """Two vehicles 1 m apart east-west hold their points with a 0.1 kg payload 1 m
    below, in a steady 3 m/s north wind. The payload hangs as a pendulum about the
    line through the vehicles: its drag c (wind - v) against the lateral stiffness
    M g / h swings it north by h sin(atan(F / (M g))), 61 mm.

    (Measured 60.6-60.9 mm over six seeds, 0.3 mm with the payload drag off; the
    vehicles' own drag and their hold loops do not move the mean.)"""
    hang, mass, wind = 1.0, 0.1, 3.0
    config = dataclasses.replace(load_world_config(DEFAULT_WORLD_CONFIG),
                                 wind=WindConfig(mean_ned=(wind, 0.0, 0.0)))
    layout = ring_layout(2, spacing=1.0, hang_depth=hang, phase=math.pi / 2.0)
    world, autopilot = build_team(layout, payload_mass=mass, rng=np.random.default_rng(1),
                                  airframe=load_airframe(DEFAULT_AIRFRAME), world_config=config,
                                  autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    take_off(world, autopilot, 2.0)
    world.run(autopilot, 4.0)  # the swing from the lift-off decays (drag only: slowly)
    offsets = []
    for _ in range(12 * 64):  # 12 s, six pendulum periods, well inside the hold timeout
        world.run(autopilot, 1.0 / 64.0)
        offsets.append(world.payload_p_ned - world.p_ned.mean(axis=0))
    assert all(m == SimMode.HOLD for m in autopilot.modes)
    drag = config.payload_drag_coefficient * wind
    deflection = hang * math.sin(math.atan(drag / (mass * config.gravity)))
    mean = np.mean(offsets, axis=0)
    assert mean[0] == pytest.approx(deflection, rel=0.03), (mean, deflection)
    assert mean[2] == pytest.approx(math.sqrt(hang**2 - deflection**2), abs=0.005), mean


def resting_team(config: WorldConfig) -> World:
    """The paper's team resting on the ground, rotors off: only the sensors change."""
    layout = paper_square()
    return World(airframe=load_airframe(DEFAULT_AIRFRAME), config=config, p0_ned=layout.p0_ned,
                 rope_length=layout.rope_length, payload_mass=0.4,
                 payload_p0_ned=layout.payload_p0_ned, rng=np.random.default_rng(5))


def attitude_error(q_true: np.ndarray, q_meas: np.ndarray) -> np.ndarray:
    """(N, 3) small rotation vector from the true to the measured attitude (body), rad."""
    out = np.empty((q_true.shape[0], 3))
    for i, (a, b) in enumerate(zip(q_true, q_meas, strict=True)):
        w, x, y, z = quat_multiply(a[0], -a[1], -a[2], -a[3], *b)
        out[i] = 2.0 * math.copysign(1.0, w) * np.array([x, y, z])
    return out


@pytest.mark.parametrize("imu_hz, pose_hz, noise", [
    (256.0, 64.0, (0.5, 0.02, 0.01, 0.05, 0.01)),
    (1024.0, 32.0, (0.1, 0.001, 0.0005, 0.003, 0.002)),
    (128.0, 256.0, (0.3, 0.005, 0.002, 0.01, 0.003)),
])
def test_sensors_deliver_their_configured_rates_and_noise(
        imu_hz: float, pose_hz: float, noise: tuple[float, ...]) -> None:
    """The autopilot's timing and its filters rest on these rates and noise levels."""
    names = ("accel_noise_std", "gyro_noise_std", "position_noise_std", "velocity_noise_std",
             "attitude_noise_std")
    config = dataclasses.replace(load_world_config(DEFAULT_WORLD_CONFIG), sensors=SensorConfig(
        imu_rate_hz=imu_hz, pose_rate_hz=pose_hz, **dict(zip(names, noise, strict=True))))
    world = resting_team(config)
    meas, off, dt = world.measurements(), np.zeros((4, 4)), 1.0 / world.physics_rate_hz
    # Rates: one physics step at a time for 0.25 s, noting the steps that bring samples.
    imu_at, pose_at = [], []
    imu_before = np.hstack([meas.accel_body, meas.gyro_body])
    pose_before = np.hstack([meas.p_ned, meas.v_ned, meas.q_wxyz])
    for k in range(1, round(0.25 * world.physics_rate_hz) + 1):
        world.step(off, dt)
        imu_now = np.hstack([meas.accel_body, meas.gyro_body])
        pose_now = np.hstack([meas.p_ned, meas.v_ned, meas.q_wxyz])
        if not np.array_equal(imu_now, imu_before):
            imu_at.append(k)
        if not np.array_equal(pose_now, pose_before):
            pose_at.append(k)
        imu_before, pose_before = imu_now, pose_now
    imu_every = round(world.physics_rate_hz / imu_hz)
    pose_every = round(world.physics_rate_hz / pose_hz)
    assert imu_at == list(range(imu_every, len(imu_at) * imu_every + 1, imu_every))
    assert len(imu_at) == 0.25 * imu_hz
    assert pose_at == list(range(pose_every, len(pose_at) * pose_every + 1, pose_every))
    assert len(pose_at) == 0.25 * pose_hz
    assert np.all(meas.pose_seq == 0.25 * pose_hz)
    # Noise: measurement minus truth at 1000 instants when both sensors just sampled.
    errors = []
    for _ in range(1000):
        world.step(off, max(imu_every, pose_every) * dt)
        errors.append(np.hstack([meas.accel_body - world.specific_force_body,
                                 meas.gyro_body - world.omega_body,
                                 meas.p_ned - world.p_ned, meas.v_ned - world.v_ned,
                                 attitude_error(world.q_wxyz, meas.q_wxyz)]))
    per_channel = np.array(errors).reshape(-1, 15)  # 4000 samples of 5 sensors x 3 axes
    expected = np.repeat(noise, 3)
    # 4000 samples: a standard deviation is good to 1.1 %, a mean to 1.6 % of sigma.
    assert per_channel.std(axis=0) == pytest.approx(expected, rel=0.05)
    assert np.all(np.abs(per_channel.mean(axis=0)) < 0.08 * expected)
    # Every axis of every sensor draws its own noise.
    correlation = np.corrcoef(per_channel.T) - np.eye(15)
    assert np.abs(correlation).max() < 0.1


@pytest.mark.parametrize("time_constant", [0.02, 0.05])
def test_rotor_speed_follows_its_command_with_a_first_order_lag(time_constant: float) -> None:
    """The attitude INDI's actuator model assumes this lag; its time constant is the
    airframe's, and commands outside [0, rotor_speed_max] are clipped."""
    airframe = dataclasses.replace(load_airframe(DEFAULT_AIRFRAME),
                                   rotor_time_constant=time_constant)
    world = aloft(airframe)
    dt = 1.0 / world.physics_rate_hz
    cmd = np.array([[700.0, 400.0, 5000.0, -300.0]])
    target = np.array([700.0, 400.0, airframe.rotor_speed_max, 0.0])
    speeds = []
    for _ in range(round(5.0 * time_constant / dt)):
        world.step(cmd, dt)
        speeds.append(world.rotor_speed[0])
    t = dt * np.arange(1, len(speeds) + 1)
    response = np.outer(1.0 - np.exp(-t / time_constant), target)
    assert np.array(speeds) == pytest.approx(response, rel=1e-12, abs=1e-9)
    # 63 % (1 - 1/e) is reached in the physics step that contains one time constant
    # (for 20 ms: 0.63248 after 41 steps of 1/2048 s, 40.96 steps being 20 ms).
    crossing = int(np.argmax(np.array(speeds)[:, 0] >= (1.0 - math.exp(-1.0)) * target[0]))
    assert crossing == math.ceil(time_constant / dt) - 1
    # Released, the speeds decay with the same time constant.
    world.step(np.zeros((1, 4)), round(time_constant / dt) * dt)
    assert world.rotor_speed[0] == pytest.approx(speeds[-1] * math.exp(-round(
        time_constant / dt) * dt / time_constant), rel=1e-12)


@pytest.mark.parametrize("roll, pitch, yaw, rotor_speed", [
    (0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 1.0, 800.0), (0.3, -0.2, 2.0, 700.0)])
def test_thrust_and_gravity_accelerate_the_body_as_newton_says(
        roll: float, pitch: float, yaw: float, rotor_speed: float) -> None:
    """Equal rotors make no torque; the thrust k_f w^2 along -z_body and gravity give
    a = g e_z - (T / m) R e_z, integrated semi-implicitly (velocity first)."""
    airframe = dataclasses.replace(load_airframe(DEFAULT_AIRFRAME), drag_coefficient=0.0)
    world = aloft(airframe)
    world.state.q_wxyz[0] = euler_to_quat(roll, pitch, yaw)
    world.state.rotor_speed[:] = rotor_speed
    n, dt = 512, 1.0 / world.physics_rate_hz
    world.step(np.full((1, 4), rotor_speed), n * dt)
    r = np.array(quat_to_rotation(*euler_to_quat(roll, pitch, yaw))).reshape(3, 3)
    thrust = 4.0 * airframe.thrust_coefficient * rotor_speed**2
    accel = np.array([0.0, 0.0, world.config.gravity]) - thrust / airframe.mass * r[:, 2]
    assert world.v_ned[0] == pytest.approx(accel * n * dt, abs=1e-9)
    assert world.p_ned[0] - [0.0, 0.0, -500.0] == pytest.approx(
        accel * dt**2 * n * (n + 1) / 2.0, abs=1e-9)
    assert world.q_wxyz[0] == pytest.approx(euler_to_quat(roll, pitch, yaw), abs=1e-12)
    assert world.omega_body[0] == pytest.approx(np.zeros(3), abs=1e-12)


def test_a_free_spinning_body_keeps_its_angular_momentum_and_energy() -> None:
    """Euler's equations with the gyroscopic term: spun about the intermediate axis
    (pitch) the body tumbles, yet J w seen from NED and the rotational energy stay."""
    airframe = load_airframe(DEFAULT_AIRFRAME)
    world = aloft(airframe)
    inertia = np.array(airframe.inertia)
    world.state.omega_body[0] = [2.0, 5.0, 1.0]

    def momentum_and_energy() -> tuple[np.ndarray, float]:
        r = np.array(quat_to_rotation(*world.state.q_wxyz[0])).reshape(3, 3)
        omega = world.state.omega_body[0]
        return r @ (inertia * omega), 0.5 * float(inertia @ omega**2)

    momentum, energy = momentum_and_energy()
    roll_rates = []
    for _ in range(32):
        world.step(np.zeros((1, 4)), 1.0 / 16.0)
        now, e = momentum_and_energy()
        # Semi-implicit Euler at 2048 Hz: measured drift at most 0.06 % over 2 s.
        assert np.linalg.norm(now - momentum) < 2e-3 * np.linalg.norm(momentum)
        assert e == pytest.approx(energy, rel=2e-3)
        roll_rates.append(world.state.omega_body[0, 0])
    assert min(roll_rates) < -2.0  # it tumbled: the roll rate reversed
