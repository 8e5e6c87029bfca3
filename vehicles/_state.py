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

from gcs.common import STANDARD_GRAVITY
from gcs.wire import SetpointKind, SimMode
from vehicles._airframe import Airframe
from vehicles._butterworth import butterworth2
from vehicles._config import AutopilotConfig
from vehicles._rotors import effectiveness_matrix

__all__ = [
    "ACCEL_SIGNALS",
    "GRAVITY",
    "RATE_SIGNALS",
    "SHARED_SETTINGS",
    "AutopilotParams",
    "AutopilotState",
    "Measurements",
    "make_autopilot_params",
    "make_autopilot_state",
    "make_measurements",
    "write_vehicle_params",
]

GRAVITY = STANDARD_GRAVITY  # one gravity for the autopilot, the simulator and the analysis
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
    """(N, 3) measured position (motion capture or GNSS), m, in the sensor frame: the world's
    NED frame, which each autopilot ties to its own local frame by its origin
    (:attr:`AutopilotState.origin_ned`)."""
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
    """(N, 3) position estimate (latest pose sample), m, in the vehicle's local frame."""
    origin_ned: np.ndarray
    """(N, 3) the vehicle's local origin in the sensor frame, m: its local NED frame is the
    sensor frame shifted there (a real autopilot's EKF origin). Zero: the frames agree."""
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
        p_est=np.zeros((n, 3)), origin_ned=np.zeros((n, 3)), v_est=np.zeros((n, 3)),
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
    """Constants of the kernel, derived from the airframe model and the configuration.

    The airframe's and the loop's are shared; the tunable ones are (N,) arrays (gains
    (N, 3)), row ``i`` vehicle ``i``'s, so each vehicle's parameters can be set on their
    own (PARAM_SET) while the team flies.
    """

    dt: float
    gravity: float
    mass: float
    thrust_coefficient: float
    rotor_speed_max: float
    actuator_alpha: float
    """per-step gain of the first-order actuator model, 1 - exp(-dt / tau)."""
    inertia: np.ndarray
    effectiveness_inv: np.ndarray
    """(4, 4) inverse of :func:`vehicles._rotors.effectiveness_matrix`."""
    accel_coef: np.ndarray
    rate_coef: np.ndarray
    rotor_speed_idle: np.ndarray
    attitude_gain: np.ndarray
    """(N, 3)."""
    rate_gain: np.ndarray
    """(N, 3)."""
    bank_max: np.ndarray
    accel_error_max_xy: np.ndarray
    accel_error_max_z: np.ndarray
    altitude_kp: np.ndarray
    altitude_kv: np.ndarray
    hold_kp: np.ndarray
    hold_kv: np.ndarray
    climb_rate: np.ndarray
    land_speed: np.ndarray
    takeoff_tolerance: np.ndarray
    setpoint_timeout: np.ndarray
    hold_timeout: np.ndarray
    ground_clearance: np.ndarray
    touchdown_time: np.ndarray
    thrust_floor: np.ndarray
    attitude_correction_gain: np.ndarray


SHARED_SETTINGS = ("rate_hz", "accel_filter_cutoff_hz", "rate_filter_cutoff_hz")
"""Configuration fields every vehicle of one :class:`AutopilotParams` shares (the loop
period and the filter coefficients): :func:`write_vehicle_params` cannot change them."""


def make_autopilot_params(airframe: Airframe, config: AutopilotConfig,
                          n_vehicles: int = 1) -> AutopilotParams:
    """Kernel constants for an airframe model (the autopilot's belief, not the truth), every
    vehicle with ``config``."""
    dt = 1.0 / config.rate_hz
    n = n_vehicles
    prm = AutopilotParams(
        dt=dt, gravity=GRAVITY, mass=float(airframe.mass),
        thrust_coefficient=float(airframe.thrust_coefficient),
        rotor_speed_max=float(airframe.rotor_speed_max),
        actuator_alpha=1.0 - math.exp(-dt / airframe.rotor_time_constant),
        inertia=np.array(airframe.inertia, dtype=np.float64),
        effectiveness_inv=np.linalg.inv(effectiveness_matrix(airframe)),
        accel_coef=butterworth2(config.accel_filter_cutoff_hz, config.rate_hz),
        rate_coef=butterworth2(config.rate_filter_cutoff_hz, config.rate_hz),
        rotor_speed_idle=np.zeros(n), attitude_gain=np.zeros((n, 3)),
        rate_gain=np.zeros((n, 3)), bank_max=np.zeros(n), accel_error_max_xy=np.zeros(n),
        accel_error_max_z=np.zeros(n), altitude_kp=np.zeros(n), altitude_kv=np.zeros(n),
        hold_kp=np.zeros(n), hold_kv=np.zeros(n), climb_rate=np.zeros(n),
        land_speed=np.zeros(n), takeoff_tolerance=np.zeros(n), setpoint_timeout=np.zeros(n),
        hold_timeout=np.zeros(n), ground_clearance=np.zeros(n), touchdown_time=np.zeros(n),
        thrust_floor=np.zeros(n), attitude_correction_gain=np.zeros(n))
    for i in range(n):
        write_vehicle_params(prm, i, airframe, config)
    return prm


def write_vehicle_params(prm: AutopilotParams, i: int, airframe: Airframe,
                         config: AutopilotConfig) -> None:
    """Give vehicle ``i`` the tunable constants of ``config`` (its :data:`SHARED_SETTINGS`
    are not read: they belong to every vehicle)."""
    for name in _AS_CONFIGURED:
        getattr(prm, name)[i] = getattr(config, name)
    prm.rotor_speed_idle[i] = airframe.rotor_speed_max * math.sqrt(config.idle_thrust_fraction)
    prm.bank_max[i] = math.radians(config.bank_max_deg)
    prm.thrust_floor[i] = config.thrust_floor_fraction * airframe.mass * GRAVITY


_AS_CONFIGURED = ("attitude_gain", "rate_gain", "accel_error_max_xy", "accel_error_max_z",
                  "altitude_kp", "altitude_kv", "hold_kp", "hold_kv", "climb_rate", "land_speed",
                  "takeoff_tolerance", "setpoint_timeout", "hold_timeout", "ground_clearance",
                  "touchdown_time", "attitude_correction_gain")
"""Kernel constants that are the configuration field of the same name, unchanged."""
