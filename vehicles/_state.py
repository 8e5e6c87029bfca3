"""Arrays the autopilot kernel reads and writes, batched over vehicles.

NamedTuples of numpy arrays: numba compiles functions over them (and caches
the result), Python code reads them by name. Row ``i`` of every array belongs
to vehicle ``i``. Scalars that change live in length-1 arrays so the kernel can
update them in place.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gcs.wire import SetpointKind, SimMode
from vehicles._airframe import Airframe
from vehicles._butterworth import butterworth2
from vehicles._config import AutopilotConfig
from vehicles._rotors import effectiveness_matrix

__all__ = [
    "ACCEL_SIGNALS",
    "GRAVITY",
    "RATE_SIGNALS",
    "AutopilotParams",
    "AutopilotState",
    "Measurements",
    "make_autopilot_params",
    "make_autopilot_state",
    "make_measurements",
]

GRAVITY = 9.81
"""Gravity the autopilot assumes, m/s^2."""

ACCEL_SIGNALS = ("accel_n", "accel_e", "accel_d", "roll", "pitch", "thrust")
"""Signals of the acceleration INDI filter bank (one cutoff keeps them in sync)."""

RATE_SIGNALS = ("rate_x", "rate_y", "rate_z", "rotor_thrust_0", "rotor_thrust_1",
                "rotor_thrust_2", "rotor_thrust_3")
"""Signals of the attitude INDI filter bank."""


class Measurements(NamedTuple):
    """Sensor readings the autopilot consumes, latest sample of each sensor."""

    accel_body: np.ndarray
    """(N, 3) accelerometer: specific force in body FRD, m/s^2 (about -9.81 on z at rest)."""
    gyro_body: np.ndarray
    """(N, 3) gyro: body rates, rad/s."""
    p_ned: np.ndarray
    """(N, 3) measured position (motion capture), m."""
    v_ned: np.ndarray
    """(N, 3) measured velocity, m/s."""
    q_wxyz: np.ndarray
    """(N, 4) measured attitude R_ned_body as a quaternion."""
    pose_seq: np.ndarray
    """(N,) int64 number of pose samples so far; 0 means none yet."""


def make_measurements(n_vehicles: int) -> Measurements:
    """Zeroed measurement arrays (identity attitude, no pose sample yet)."""
    q = np.zeros((n_vehicles, 4))
    q[:, 0] = 1.0
    return Measurements(np.zeros((n_vehicles, 3)), np.zeros((n_vehicles, 3)),
                        np.zeros((n_vehicles, 3)), np.zeros((n_vehicles, 3)), q,
                        np.zeros(n_vehicles, dtype=np.int64))


class AutopilotState(NamedTuple):
    """Everything the autopilot remembers between steps."""

    t: np.ndarray
    """(1,) autopilot time, s."""
    mode: np.ndarray
    """(N,) int64 :class:`SimMode` values."""
    q_est: np.ndarray
    """(N, 4) attitude estimate (gyro propagation corrected by pose samples)."""
    p_est: np.ndarray
    """(N, 3) position estimate (latest pose sample), m."""
    v_est: np.ndarray
    """(N, 3) velocity estimate (latest pose sample), m/s."""
    pose_seq_seen: np.ndarray
    """(N,) int64 pose sample counter last used."""
    accel_filter: np.ndarray
    """(N, 6, 2) biquad states of :data:`ACCEL_SIGNALS`."""
    accel_filtered: np.ndarray
    """(N, 6) filtered :data:`ACCEL_SIGNALS` (m/s^2, rad, N)."""
    rate_filter: np.ndarray
    """(N, 7, 2) biquad states of :data:`RATE_SIGNALS`."""
    rate_filtered: np.ndarray
    """(N, 7) filtered :data:`RATE_SIGNALS` (rad/s, N)."""
    rate_filtered_prev: np.ndarray
    """(N, 3) filtered body rates one step ago, rad/s."""
    rotor_speed_model: np.ndarray
    """(N, 4) first-order actuator model of the rotor speeds, rad/s."""
    rotor_speed_cmd: np.ndarray
    """(N, 4) rotor speed commands, rad/s (the autopilot's output)."""
    sp_kind: np.ndarray
    """(N,) int64 :class:`SetpointKind` of the latest external setpoint."""
    sp_accel_ned: np.ndarray
    """(N, 3) commanded acceleration, m/s^2 (z unused for ACCEL_XY_POS_Z)."""
    sp_z_ned: np.ndarray
    """(N,) commanded z position for ACCEL_XY_POS_Z, m."""
    sp_time: np.ndarray
    """(N,) autopilot time the latest setpoint arrived, s (-inf: never)."""
    sp_yaw: np.ndarray
    """(N,) commanded heading of the latest setpoint, rad (NaN: keep the heading)."""
    yaw_hold: np.ndarray
    """(N,) commanded heading, rad."""
    p_hold: np.ndarray
    """(N, 3) position held in HOLD (x, y also in TAKEOFF and LAND), m."""
    hold_start: np.ndarray
    """(N,) time HOLD began, s."""
    z_home: np.ndarray
    """(N,) z at arming (ground level), m."""
    z_target: np.ndarray
    """(N,) TAKEOFF target z, m."""
    z_ref: np.ndarray
    """(N,) TAKEOFF ramped z reference, m."""
    touchdown_timer: np.ndarray
    """(N,) time spent on the ground in LAND, s."""
    accel_ref_ned: np.ndarray
    """(N, 3) acceleration reference nu_a of eq. (inca) used this step, m/s^2."""
    attitude_cmd: np.ndarray
    """(N, 3) commanded roll, pitch, yaw, rad."""
    thrust_cmd: np.ndarray
    """(N,) commanded total thrust, N."""


def make_autopilot_state(n_vehicles: int) -> AutopilotState:
    """State of ``n_vehicles`` disarmed autopilots at time 0."""
    n = n_vehicles
    q = np.zeros((n, 4))
    q[:, 0] = 1.0
    return AutopilotState(
        t=np.zeros(1), mode=np.full(n, int(SimMode.DISARMED), dtype=np.int64), q_est=q,
        p_est=np.zeros((n, 3)), v_est=np.zeros((n, 3)),
        pose_seq_seen=np.zeros(n, dtype=np.int64),
        accel_filter=np.zeros((n, len(ACCEL_SIGNALS), 2)),
        accel_filtered=np.zeros((n, len(ACCEL_SIGNALS))),
        rate_filter=np.zeros((n, len(RATE_SIGNALS), 2)),
        rate_filtered=np.zeros((n, len(RATE_SIGNALS))), rate_filtered_prev=np.zeros((n, 3)),
        rotor_speed_model=np.zeros((n, 4)), rotor_speed_cmd=np.zeros((n, 4)),
        sp_kind=np.full(n, int(SetpointKind.NONE), dtype=np.int64),
        sp_accel_ned=np.zeros((n, 3)), sp_z_ned=np.zeros(n), sp_time=np.full(n, -np.inf),
        sp_yaw=np.full(n, np.nan),
        yaw_hold=np.zeros(n), p_hold=np.zeros((n, 3)), hold_start=np.zeros(n),
        z_home=np.zeros(n), z_target=np.zeros(n), z_ref=np.zeros(n),
        touchdown_timer=np.zeros(n), accel_ref_ned=np.zeros((n, 3)),
        attitude_cmd=np.zeros((n, 3)), thrust_cmd=np.zeros(n))


class AutopilotParams(NamedTuple):
    """Constants of the kernel, derived from the airframe model and the configuration."""

    dt: float
    gravity: float
    mass: float
    thrust_coefficient: float
    rotor_speed_max: float
    rotor_speed_idle: float
    actuator_alpha: float
    """per-step gain of the first-order actuator model, 1 - exp(-dt / tau)."""
    inertia: np.ndarray
    effectiveness_inv: np.ndarray
    """(4, 4) inverse of :func:`vehicles._rotors.effectiveness_matrix`."""
    accel_coef: np.ndarray
    rate_coef: np.ndarray
    attitude_gain: np.ndarray
    rate_gain: np.ndarray
    bank_max: float
    accel_error_max_xy: float
    accel_error_max_z: float
    altitude_kp: float
    altitude_kv: float
    hold_kp: float
    hold_kv: float
    climb_rate: float
    land_speed: float
    takeoff_tolerance: float
    setpoint_timeout: float
    hold_timeout: float
    ground_clearance: float
    touchdown_time: float
    thrust_floor: float
    attitude_correction_gain: float


def make_autopilot_params(airframe: Airframe, config: AutopilotConfig) -> AutopilotParams:
    """Kernel constants for an airframe model (the autopilot's belief, not the truth)."""
    dt = 1.0 / config.rate_hz
    return AutopilotParams(
        dt=dt, gravity=GRAVITY, mass=float(airframe.mass),
        thrust_coefficient=float(airframe.thrust_coefficient),
        rotor_speed_max=float(airframe.rotor_speed_max),
        rotor_speed_idle=float(airframe.rotor_speed_max * math.sqrt(config.idle_thrust_fraction)),
        actuator_alpha=1.0 - math.exp(-dt / airframe.rotor_time_constant),
        inertia=np.array(airframe.inertia, dtype=np.float64),
        effectiveness_inv=np.linalg.inv(effectiveness_matrix(airframe)),
        accel_coef=butterworth2(config.accel_filter_cutoff_hz, config.rate_hz),
        rate_coef=butterworth2(config.rate_filter_cutoff_hz, config.rate_hz),
        attitude_gain=np.array(config.attitude_gain, dtype=np.float64),
        rate_gain=np.array(config.rate_gain, dtype=np.float64),
        bank_max=math.radians(config.bank_max_deg),
        accel_error_max_xy=float(config.accel_error_max_xy),
        accel_error_max_z=float(config.accel_error_max_z),
        altitude_kp=float(config.altitude_kp), altitude_kv=float(config.altitude_kv),
        hold_kp=float(config.hold_kp), hold_kv=float(config.hold_kv),
        climb_rate=float(config.climb_rate), land_speed=float(config.land_speed),
        takeoff_tolerance=float(config.takeoff_tolerance),
        setpoint_timeout=float(config.setpoint_timeout), hold_timeout=float(config.hold_timeout),
        ground_clearance=float(config.ground_clearance),
        touchdown_time=float(config.touchdown_time),
        thrust_floor=float(config.thrust_floor_fraction * airframe.mass * GRAVITY),
        attitude_correction_gain=float(config.attitude_correction_gain))
