"""The paper's team hovering with its payload matches the force analysis of section V.

Four Bebops on a 1 m square, ropes sqrt(1.25) m, 0.4 kg payload at the centre:
eq. (T) gives the rope tension, and each vehicle must tilt so that the
horizontal part of its thrust cancels the rope's horizontal pull. Real physics
and real autopilots; the payload also has to stay on the ground until the ropes
are taut.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np
import pytest

from sim import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    build_team,
    load_world_config,
    paper_square,
    take_off,
)
from sim._config import SensorConfig, WindConfig, WorldConfig
from sim._world import World
from vehicles import Autopilot, load_airframe, load_autopilot_config, quat_to_rotation

PAYLOAD_MASS = 0.4
ROPE = math.sqrt(1.25)
DIAGONAL = math.sqrt(2.0)
ALTITUDE = 1.5


def paper_tension(g: float) -> float:
    """Eq. (T): ||T|| = (M g / 4) l / sqrt(l^2 - d2^2 / 4)."""
    return PAYLOAD_MASS * g / 4.0 * ROPE / math.sqrt(ROPE**2 - DIAGONAL**2 / 4.0)


class Hover(NamedTuple):
    g: float
    vehicle_mass: float
    tension: np.ndarray  # (samples, 4) N
    tilt: np.ndarray  # (samples, 4) rad, angle of the thrust axis from the vertical
    predicted_tilt: np.ndarray  # (samples, 4) rad, from each vehicle's own rope force
    thrust_dir_dot_outward: np.ndarray  # (samples, 4)
    # The climb, every physics step (2048 Hz):
    takeoff_payload_height: np.ndarray  # (steps,) m above the ground
    takeoff_rope_slack: np.ndarray  # (steps,) bool, no rope pulls
    takeoff_lift: np.ndarray  # (steps,) sum of rope pulls upwards on the payload, N


def fly(config: WorldConfig, seed: int) -> Hover:
    airframe = load_airframe(DEFAULT_AIRFRAME)
    world, autopilot = build_team(paper_square(), payload_mass=PAYLOAD_MASS,
                                  rng=np.random.default_rng(seed), airframe=airframe,
                                  world_config=config,
                                  autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    world.run(autopilot, 1.0 / 32.0)
    for i in range(4):
        assert autopilot.arm(i).accepted
        assert autopilot.takeoff(i, ALTITUDE).accepted
    heights, slack, lift = [], [], []
    # The climb, seen every physics step: the ropes snap taut within milliseconds and
    # the payload can be airborne with slack ropes a control period later. Stepping
    # the autopilot and the world from Python is World.run's computation.
    dt = 1.0 / world.physics_rate_hz
    for _ in range(6 * round(autopilot.rate_hz)):
        command = autopilot.step(world.measurements())
        for _ in range(round(world.physics_rate_hz / autopilot.rate_hz)):
            world.step(command, dt)
            tension = world.rope_tension
            to_vehicle = world.p_ned - world.payload_p_ned
            up = -to_vehicle[:, 2] / np.linalg.norm(to_vehicle, axis=1)
            heights.append(config.ground.z_ned - world.payload_p_ned[2])
            slack.append(bool(np.all(tension == 0.0)))
            lift.append(float(np.sum(tension * up)))
    world.run(autopilot, 6.0)  # settle in HOLD

    tensions, tilts, predicted, outward = [], [], [], []
    for _ in range(4 * 64):  # 4 s at 64 Hz
        world.run(autopilot, 1.0 / 64.0)
        tension = world.rope_tension
        rope_dir = world.payload_p_ned - world.p_ned
        rope_dir /= np.linalg.norm(rope_dir, axis=1, keepdims=True)
        rope_force = tension[:, None] * rope_dir
        tilt_i, pred_i, out_i = [], [], []
        for i in range(4):
            thrust_axis = -np.array(quat_to_rotation(*world.state.q_wxyz[i])).reshape(3, 3)[:, 2]
            tilt_i.append(math.acos(-thrust_axis[2]))
            pred_i.append(math.atan2(math.hypot(rope_force[i, 0], rope_force[i, 1]),
                                     airframe.mass * config.gravity + rope_force[i, 2]))
            horizontal = thrust_axis[:2] / np.linalg.norm(thrust_axis[:2])
            out_i.append(float(-horizontal @ rope_dir[i, :2] / np.linalg.norm(rope_dir[i, :2])))
        tensions.append(tension)
        tilts.append(tilt_i)
        predicted.append(pred_i)
        outward.append(out_i)
    return Hover(config.gravity, airframe.mass, np.array(tensions), np.array(tilts),
                 np.array(predicted), np.array(outward), np.array(heights), np.array(slack),
                 np.array(lift))


def silent_world() -> WorldConfig:
    """The default world with noise-free sensors."""
    silent = SensorConfig(accel_noise_std=0.0, gyro_noise_std=0.0, position_noise_std=0.0,
                          velocity_noise_std=0.0, attitude_noise_std=0.0)
    return dataclasses.replace(load_world_config(DEFAULT_WORLD_CONFIG), sensors=silent)


@pytest.fixture(scope="module")
def noisy() -> Hover:
    """Default world: sensor noise on."""
    return fly(load_world_config(DEFAULT_WORLD_CONFIG), seed=11)


@pytest.fixture(scope="module")
def quiet() -> Hover:
    """Noise-free sensors: the symmetric equilibrium the paper analyses."""
    return fly(silent_world(), seed=11)


def test_each_rope_carries_the_paper_tension_in_the_symmetric_equilibrium(quiet: Hover) -> None:
    expected = paper_tension(quiet.g)
    per_rope = quiet.tension.mean(axis=0)
    assert np.all(np.abs(per_rope / expected - 1.0) < 0.02), (per_rope, expected)


def test_mean_rope_tension_matches_the_paper_with_sensor_noise(noisy: Hover) -> None:
    # Four stiff ropes to one point are statically indeterminate: how the load
    # splits between the two diagonals depends on sub-millimetre position
    # differences, which sensor noise sets. The load itself, the mean tension,
    # does not; that is what eq. (T) predicts.
    expected = paper_tension(noisy.g)
    assert abs(noisy.tension.mean() / expected - 1.0) < 0.02, (noisy.tension.mean(), expected)
    per_rope = noisy.tension.mean(axis=0)
    # The split: the payload's horizontal balance makes the two ropes of a diagonal
    # (vehicles 0 and 2, 1 and 3) pull alike (measured within 1.6 % of eq. (T) over
    # eight seeds), and one diagonal carries at most a quarter more than eq. (T)
    # (measured +-15 % here, at most +-23 % over eight seeds).
    assert abs(per_rope[0] - per_rope[2]) < 0.03 * expected, per_rope
    assert abs(per_rope[1] - per_rope[3]) < 0.03 * expected, per_rope
    assert np.all(np.abs(per_rope / expected - 1.0) < 0.25), per_rope / expected


def test_vehicles_tilt_as_the_force_diagram_predicts(quiet: Hover, noisy: Hover) -> None:
    g, m = quiet.g, quiet.vehicle_mass
    t = paper_tension(g)
    t_h = t * (DIAGONAL / 2.0) / ROPE
    t_v = t * math.sqrt(ROPE**2 - DIAGONAL**2 / 4.0) / ROPE
    paper_tilt = math.atan(t_h / (m * g + t_v))  # 9.27 degrees
    # Noise-free the equilibrium is exact up to the rope stretch (0.25 mm):
    # 0.05 degrees is 1 % of the horizontal force.
    assert np.all(np.abs(quiet.tilt.mean(axis=0) - paper_tilt) < math.radians(0.05))
    # With noise each vehicle balances its own rope: the 4 s average of the
    # thrust tilt matches the tilt that its measured rope force requires.
    # Noise jitters the attitude by about 0.3 degrees per sample; averaged over
    # 256 samples (and with the small drag of the hovering jitter) 0.2 degrees
    # is a 2 % bound on the horizontal force balance.
    assert np.all(np.abs(noisy.tilt.mean(axis=0) - noisy.predicted_tilt.mean(axis=0))
                  < math.radians(0.2))
    assert np.all(noisy.tilt.mean(axis=0) > math.radians(5.0))
    # The thrust leans away from the payload (it pulls the vehicle inwards).
    assert np.all(noisy.thrust_dir_dot_outward.mean(axis=0) > 0.99)


@pytest.mark.parametrize("case", ["quiet", "noisy"])
def test_payload_stays_on_the_ground_until_the_ropes_lift_it(
        case: str, request: pytest.FixtureRequest) -> None:
    hover: Hover = request.getfixturevalue(case)
    slack = hover.takeoff_rope_slack
    assert slack[0] and not slack[-1]
    first_taut = int(np.argmax(~slack))
    # Resting in ground contact the payload sinks about M g / k = 2 mm.
    assert np.all(hover.takeoff_payload_height[:first_taut] < 0.0)
    # It leaves the ground (its contact unloaded) only once the ropes pull up its
    # weight, and in that step they still do (measured at least 1.7 times the weight;
    # a step later the snap may have thrown it up on slack ropes).
    weight = PAYLOAD_MASS * hover.g
    first_pull = int(np.argmax(hover.takeoff_lift >= weight))
    first_up = int(np.argmax(hover.takeoff_payload_height > 0.0))
    assert first_taut <= first_pull < first_up
    assert np.all(hover.takeoff_payload_height[:first_pull] < 0.0)
    assert hover.takeoff_lift[first_up] >= 0.95 * weight, hover.takeoff_lift[first_up] / weight
    assert hover.takeoff_payload_height[-1] > 0.5


def hovering(config: WorldConfig) -> tuple[World, Autopilot]:
    """The paper's team after the climb and 4 s of HOLD: payload hanging, settled."""
    world, autopilot = build_team(paper_square(), payload_mass=PAYLOAD_MASS,
                                  rng=np.random.default_rng(11),
                                  airframe=load_airframe(DEFAULT_AIRFRAME), world_config=config,
                                  autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    take_off(world, autopilot, ALTITUDE)
    world.run(autopilot, 4.0)
    return world, autopilot


class StepForces(NamedTuple):
    thrust: np.ndarray  # (N,) rotor thrust of each vehicle, N
    tension: np.ndarray  # (N,) N
    vehicle_drag: np.ndarray  # (N, 3) NED, N
    payload_drag: np.ndarray  # (3,) NED, N


def one_physics_step(world: World, autopilot: Autopilot) -> StepForces:
    """One physics step from a known state, checked against the model's equations:
    each specific force is (thrust along -z_body + rope pull towards the payload
    - c_d (v - wind)) / m, and the airborne payload accelerates by
    (rope pulls - c_payload (v_payload - wind)) / M + g. The drag terms come from the
    configured coefficients, so a physics that drops one fails here."""
    airframe, g = world.airframe, world.config.gravity
    p, v, q = world.p_ned, world.v_ned, world.q_wxyz
    payload_p, payload_v = world.payload_p_ned, world.payload_v_ned
    assert payload_p[2] < world.config.ground.z_ned - 0.1  # airborne: no ground contact
    dt = 1.0 / world.physics_rate_hz
    world.step(autopilot.step(world.measurements()), dt)
    wind = world.wind_ned
    thrust = airframe.thrust_coefficient * np.sum(world.rotor_speed**2, axis=1)
    tension = world.rope_tension
    to_vehicle = (p - payload_p) / np.linalg.norm(p - payload_p, axis=1, keepdims=True)
    vehicle_drag = -airframe.drag_coefficient * (v - wind)
    for i in range(world.n_vehicles):
        r = np.array(quat_to_rotation(*q[i])).reshape(3, 3)
        force = -thrust[i] * r[:, 2] - tension[i] * to_vehicle[i] + vehicle_drag[i]
        assert world.specific_force_body[i] == pytest.approx(r.T @ force / airframe.mass,
                                                             abs=1e-9)
    payload_drag = -world.config.payload_drag_coefficient * (payload_v - wind)
    payload_accel = (tension @ to_vehicle + payload_drag) / PAYLOAD_MASS + [0.0, 0.0, g]
    assert (world.payload_v_ned - payload_v) / dt == pytest.approx(payload_accel, abs=1e-9)
    return StepForces(thrust, tension, vehicle_drag, payload_drag)


def test_the_accelerometer_feels_the_rope() -> None:
    """INDI needs no payload model because the accelerometer measures the rope: its
    specific force is (thrust + rope + drag) / m, which in hover is -g (about -9.69 on
    z_body at the 9.3 degree tilt), not the thrust alone (-T / m, about -12.4)."""
    world, autopilot = hovering(silent_world())
    # Noise-free, each accelerometer sample is the specific force of its step ...
    np.testing.assert_array_equal(world.measurements().accel_body, world.specific_force_body)
    # ... which, hovering, is what holds the vehicle up against gravity.
    g = world.config.gravity
    in_ned = []
    for _ in range(512):
        world.run(autopilot, 1.0 / 512.0)
        in_ned.append([np.array(quat_to_rotation(*q)).reshape(3, 3) @ f
                       for q, f in zip(world.state.q_wxyz, world.specific_force_body,
                                       strict=True)])
    assert np.mean(in_ned, axis=0) == pytest.approx(np.tile([0.0, 0.0, -g], (4, 1)), abs=0.02)
    # One physics step: thrust, rope and drag make the specific force exactly.
    forces = one_physics_step(world, autopilot)
    assert np.all(np.abs(forces.tension / paper_tension(g) - 1.0) < 0.02), forces.tension
    # The rope's share is what the accelerometer adds to thrust alone.
    assert np.all(world.specific_force_body[:, 2] + forces.thrust / world.airframe.mass > 2.0)


def test_steady_wind_drags_vehicles_and_payload_as_the_model_states() -> None:
    """Drag is linear in the airspeed v - wind, on each vehicle (airframe c_d) and on
    the payload (its own coefficient). Hovering in a steady 2.3 m/s wind with a
    vertical part, one physics step holds both drag terms exactly."""
    config = dataclasses.replace(silent_world(), wind=WindConfig(mean_ned=(2.0, -1.0, 0.5)))
    world, autopilot = hovering(config)
    forces = one_physics_step(world, autopilot)
    # The terms are far above the 1e-9 tolerance: 0.11 N per vehicle (0.29 m/s^2 of
    # specific force) and 0.046 N on the payload (0.11 m/s^2).
    assert np.all(np.linalg.norm(forces.vehicle_drag, axis=1) > 0.1), forces.vehicle_drag
    assert np.linalg.norm(forces.payload_drag) > 0.04, forces.payload_drag
