"""Arrays of the physics kernel: the world's true state and its constants.

NamedTuples of numpy arrays, like the autopilot's, so numba compiles (and
caches) the stepping loops over them. Row ``i`` belongs to vehicle ``i``; the
payload is a single point mass.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from sim._config import WorldConfig
from vehicles import Airframe, rotor_layout

__all__ = ["PhysicsParams", "PhysicsState", "make_physics_params", "make_physics_state"]


class PhysicsState(NamedTuple):
    """True state of vehicles, rotors, payload, ropes and wind."""

    step: np.ndarray
    """(1,) int64 physics steps taken; time is step / physics_rate_hz."""
    p_ned: np.ndarray
    """(N, 3) vehicle centre-of-mass positions, m."""
    v_ned: np.ndarray
    """(N, 3) vehicle velocities, m/s."""
    q_wxyz: np.ndarray
    """(N, 4) vehicle attitudes R_ned_body."""
    omega_body: np.ndarray
    """(N, 3) body rates, rad/s."""
    rotor_speed: np.ndarray
    """(N, 4) rotor speeds, rad/s (order of :func:`vehicles.rotor_layout`)."""
    payload_p_ned: np.ndarray
    """(3,) payload position, m."""
    payload_v_ned: np.ndarray
    """(3,) payload velocity, m/s."""
    rope_tension: np.ndarray
    """(N,) rope tensions of the last step, N (0 when slack)."""
    specific_force_body: np.ndarray
    """(N, 3) true specific force (non-gravitational force / mass) in body FRD, m/s^2."""
    gust_ned: np.ndarray
    """(3,) current gust velocity on top of the mean wind, m/s."""


def make_physics_state(p0_ned: np.ndarray, yaw0: np.ndarray,
                       payload_p0_ned: np.ndarray) -> PhysicsState:
    """Everything at rest: vehicles level at ``p0_ned`` with headings ``yaw0`` (rad)."""
    n = p0_ned.shape[0]
    q = np.zeros((n, 4))
    q[:, 0] = np.cos(0.5 * yaw0)
    q[:, 3] = np.sin(0.5 * yaw0)
    return PhysicsState(
        step=np.zeros(1, dtype=np.int64), p_ned=np.array(p0_ned, dtype=np.float64),
        v_ned=np.zeros((n, 3)), q_wxyz=q, omega_body=np.zeros((n, 3)),
        rotor_speed=np.zeros((n, 4)), payload_p_ned=np.array(payload_p0_ned, dtype=np.float64),
        payload_v_ned=np.zeros(3), rope_tension=np.zeros(n), specific_force_body=np.zeros((n, 3)),
        gust_ned=np.zeros(3))


class PhysicsParams(NamedTuple):
    """Constants of the physics kernel (SI units; see :mod:`sim._config` for meanings)."""

    dt: float
    gravity: float
    mass: float
    inertia: np.ndarray
    thrust_coefficient: float
    torque_ratio: float
    rotor_xy: np.ndarray
    rotor_spin: np.ndarray
    rotor_alpha: float
    """per-step gain of the rotor speed lag, 1 - exp(-dt / tau)."""
    rotor_speed_max: float
    drag_coefficient: float
    rope_length: np.ndarray
    rope_stiffness: float
    rope_damping: float
    payload_mass: float
    payload_drag: float
    ground_z: float
    ground_stiffness: float
    ground_damping: float
    friction_coefficient: float
    friction_damping: float
    wind_mean: np.ndarray
    gust_decay: float
    """per-step gust decay exp(-dt / T)."""
    gust_drive: float
    """per-step gust noise scale sigma sqrt(1 - decay^2), m/s."""
    imu_every: int
    pose_every: int
    accel_noise_std: float
    gyro_noise_std: float
    position_noise_std: float
    velocity_noise_std: float
    attitude_noise_std: float


def make_physics_params(airframe: Airframe, config: WorldConfig, rope_length: np.ndarray,
                        payload_mass: float) -> PhysicsParams:
    """Kernel constants for the true airframe and the world configuration."""
    dt = 1.0 / config.physics_rate_hz
    layout = rotor_layout(airframe)
    gust_decay = math.exp(-dt / config.wind.gust_time_constant)
    sensors = config.sensors
    return PhysicsParams(
        dt=dt, gravity=float(config.gravity), mass=float(airframe.mass),
        inertia=np.array(airframe.inertia, dtype=np.float64),
        thrust_coefficient=float(airframe.thrust_coefficient),
        torque_ratio=float(airframe.torque_ratio), rotor_xy=layout.xy_body,
        rotor_spin=layout.spin, rotor_alpha=1.0 - math.exp(-dt / airframe.rotor_time_constant),
        rotor_speed_max=float(airframe.rotor_speed_max),
        drag_coefficient=float(airframe.drag_coefficient),
        rope_length=np.array(rope_length, dtype=np.float64),
        rope_stiffness=float(config.rope.stiffness), rope_damping=float(config.rope.damping),
        payload_mass=float(payload_mass), payload_drag=float(config.payload_drag_coefficient),
        ground_z=float(config.ground.z_ned), ground_stiffness=float(config.ground.stiffness),
        ground_damping=float(config.ground.damping),
        friction_coefficient=float(config.ground.friction_coefficient),
        friction_damping=float(config.ground.friction_damping),
        wind_mean=np.array(config.wind.mean_ned, dtype=np.float64), gust_decay=gust_decay,
        gust_drive=float(config.wind.gust_std * math.sqrt(1.0 - gust_decay**2)),
        imu_every=round(config.physics_rate_hz / sensors.imu_rate_hz),
        pose_every=round(config.physics_rate_hz / sensors.pose_rate_hz),
        accel_noise_std=float(sensors.accel_noise_std),
        gyro_noise_std=float(sensors.gyro_noise_std),
        position_noise_std=float(sensors.position_noise_std),
        velocity_noise_std=float(sensors.velocity_noise_std),
        attitude_noise_std=float(sensors.attitude_noise_std))
