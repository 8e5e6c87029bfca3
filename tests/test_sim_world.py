"""The world as a library: configs, inputs, determinism, sensors at rest, one kernel path."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import yaml

from gcs.typed_config import ConfigError
from sim.config import SensorConfig, WorldConfig, load_world_config
from sim.layout import paper_square
from sim.scenario import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    build_team,
    take_off,
)
from sim.world import World
from vehicles.airframe import bebop2, load_airframe
from vehicles.autopilot import Autopilot
from vehicles.config import AutopilotConfig, load_autopilot_config


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


def test_wind_pushes_the_payload_and_gusts_follow_their_statistics() -> None:
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
    # Drag of the mean wind blows the hanging payload downwind (north).
    assert world.payload_p_ned[0] > 0.005
