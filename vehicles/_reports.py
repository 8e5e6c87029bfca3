"""Telemetry messages of one simulated vehicle, built from its autopilot's own state.

Why: the GCS must see a simulated vehicle exactly as it sees a real one, so
each message reports what an onboard autopilot knows (its position and
attitude estimates, its IMU and GNSS, its battery monitor), never the
simulator's truth. It presents itself as PX4 does (HEARTBEAT, AUTOPILOT_VERSION)
so other ground stations understand it. Times are sim time since the start of
the run (``time_boot``). Global positions are the sensor frame's NED positions
on the WGS-84 tangent plane at the world's geodetic reference
(:mod:`gcs.wire._geodetic`); altitudes are heights above the ellipsoid (no geoid),
sent where MAVLink says AMSL too.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from gcs.wire import Geodetic, MavMessage, SimMode, mavlink, ned_to_geodetic, px4_base_mode
from vehicles._autopilot import Autopilot
from vehicles._battery import BatteryReading
from vehicles._quaternion import euler_to_quat, quat_to_euler
from vehicles._state import Measurements
from vehicles._streams import TelemetryMessage

__all__ = [
    "CAPABILITIES",
    "FLIGHT_SW_VERSION",
    "LOW_BATTERY",
    "CommCounters",
    "Home",
    "Identity",
    "VehicleView",
    "build_report",
    "time_boot_ms",
]

LOW_BATTERY = 0.15
"""Remaining charge below which the battery reports unhealthy and the state CRITICAL."""

_SENSORS = (mavlink.MAV_SYS_STATUS_SENSOR_3D_GYRO | mavlink.MAV_SYS_STATUS_SENSOR_3D_ACCEL
            | mavlink.MAV_SYS_STATUS_SENSOR_VISION_POSITION
            | mavlink.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
            | mavlink.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION
            | mavlink.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL
            | mavlink.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
            | mavlink.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS | mavlink.MAV_SYS_STATUS_SENSOR_BATTERY)
"""Subsystems reported present, enabled and (battery aside) healthy."""

_IMU_FIELDS = 0b111111
"""HIGHRES_IMU ``fields_updated``: x/y/z acceleration and x/y/z gyro."""

_U16 = 0xFFFF

CAPABILITIES = (mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
                | mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
                | mavlink.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED)
"""AUTOPILOT_VERSION ``capabilities``: MAVLink 2, PX4's byte-wise parameter encoding (integer
parameters travel as their bits in ``param_value``), local NED position targets."""

FLIGHT_SW_VERSION = (1 << 24) | (14 << 16) | (0 << 8) | mavlink.FIRMWARE_VERSION_TYPE_OFFICIAL
"""AUTOPILOT_VERSION ``flight_sw_version`` in PX4's encoding (major, minor, patch, type): the
PX4 release whose MAVLink interface the simulated vehicle follows, 1.14.0."""

_CUSTOM_VERSION = b"fgc-sim\0"
"""``flight_custom_version`` (8 bytes; PX4 puts its git hash there)."""

_GPS_SATELLITES = 20


@dataclass(frozen=True)
class Identity:
    """What a vehicle is and where its sensor frame lies; fixed for a run."""

    sysid: int
    reference: Geodetic
    """Geodetic position of the sensor frame's origin (the world's NED origin)."""
    gps_accuracy_m: float = 0.01
    """Position accuracy the GNSS reports (GPS_RAW_INT eph, epv, h_acc, v_acc), m."""


@dataclass(frozen=True)
class CommCounters:
    """Link-side counts reported in SYS_STATUS (``errors_count1..3`` are this vehicle's)."""

    frames: int
    """Frames accepted."""
    dropped: int
    """Frames dropped (bad checksum, truncated, unknown, refused signature): ``errors_comm``."""
    not_for_us: int
    """Frames addressed to another system or component: ``errors_count1``."""
    garbage_bytes: int
    """Bytes outside any frame: ``errors_count2``."""
    setpoints_refused: int
    """Setpoints refused by the input checks: ``errors_count3``."""


class Home(NamedTuple):
    """Where a vehicle's home is: in the sensor frame (m) and on Earth."""

    ned: np.ndarray
    geodetic: Geodetic


@dataclass(frozen=True)
class VehicleView:
    """What a report may read: the vehicle's autopilot, sensors and battery at sim time t."""

    autopilot: Autopilot
    index: int
    measurements: Measurements
    battery: BatteryReading
    comm: CommCounters | None
    """Link counters; only SYS_STATUS needs them (None when it is not being sent)."""
    t: float
    identity: Identity
    custom_mode: int
    """PX4 ``custom_mode`` the vehicle reports (:class:`vehicles._px4_modes.Px4Modes`)."""
    home: Home | None
    """Home (None until the first position sample)."""

    @property
    def located(self) -> bool:
        """Whether the vehicle has had a position sample."""
        return bool(self.autopilot.state.pose_seq_seen[self.index] > 0)

    def origin(self) -> Geodetic:
        """The vehicle's local origin (its EKF origin)."""
        return self.geodetic(self.autopilot.state.origin_ned[self.index])

    def geodetic(self, p_sensor_ned: np.ndarray) -> Geodetic:
        """Geodetic position of a point of the sensor frame."""
        return Geodetic(*(float(v) for v in ned_to_geodetic(p_sensor_ned,
                                                            self.identity.reference)))


def build_report(mav: mavlink.MAVLink, message: TelemetryMessage,
                 view: VehicleView) -> MavMessage | None:
    """The ``message`` the vehicle sends now; None when it has nothing to say yet (a global
    position before the first position sample)."""
    return _BUILDERS[message](mav, view)


def _heartbeat(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    mode = v.autopilot.mode(v.index)
    armed = mode is not SimMode.DISARMED
    if v.battery.remaining < LOW_BATTERY:
        state = mavlink.MAV_STATE_CRITICAL
    else:
        state = mavlink.MAV_STATE_ACTIVE if armed else mavlink.MAV_STATE_STANDBY
    return mav.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_PX4,
                                px4_base_mode(v.custom_mode, armed=armed), v.custom_mode, state)


def _position(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    s, i = v.autopilot.state, v.index
    return mav.local_position_ned_encode(time_boot_ms(v.t), *(float(x) for x in s.p_est[i]),
                                         *(float(x) for x in s.v_est[i]))


def _rates(v: VehicleView) -> tuple[float, float, float]:
    r = v.autopilot.state.rate_filtered[v.index]
    return float(r[0]), float(r[1]), float(r[2])


def _attitude(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    q = v.autopilot.state.q_est[v.index]
    roll, pitch, yaw = quat_to_euler(float(q[0]), float(q[1]), float(q[2]), float(q[3]))
    return mav.attitude_encode(time_boot_ms(v.t), roll, pitch, yaw, *_rates(v))


def _attitude_quaternion(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    q = v.autopilot.state.q_est[v.index]
    return mav.attitude_quaternion_encode(time_boot_ms(v.t), *(float(x) for x in q), *_rates(v))


def _attitude_target(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    """The attitude and collective thrust the controller commands, thrust as a fraction of
    the rotors' full thrust (PX4's and ArduCopter's 0 .. 1)."""
    s, i = v.autopilot.state, v.index
    q = euler_to_quat(*(float(x) for x in s.attitude_cmd[i]))
    thrust = min(1.0, max(0.0, float(s.thrust_cmd[i]) / v.autopilot.airframe.thrust_max))
    return mav.attitude_target_encode(time_boot_ms(v.t), 0, q, 0.0, 0.0, 0.0, thrust)


def _imu(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    m, i = v.measurements, v.index
    return mav.highres_imu_encode(int(v.t * 1e6), *(float(x) for x in m.accel_body[i]),
                                  *(float(x) for x in m.gyro_body[i]), 0.0, 0.0, 0.0, 0.0, 0.0,
                                  0.0, 0.0, _IMU_FIELDS)


def _sys_status(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    b, c = v.battery, v.comm
    assert c is not None, "SYS_STATUS needs the link counters"
    health = _SENSORS if b.remaining >= LOW_BATTERY else _SENSORS & ~int(
        mavlink.MAV_SYS_STATUS_SENSOR_BATTERY)
    offered = c.frames + c.dropped
    drop_rate = round(10000 * c.dropped / offered) if offered else 0
    return mav.sys_status_encode(
        _SENSORS, _SENSORS, health, 0, min(_U16 - 1, round(b.voltage_v * 1000)),
        min(32767, round(b.current_a * 100)), round(b.remaining * 100), drop_rate,
        min(_U16, c.dropped), min(_U16, c.not_for_us), min(_U16, c.garbage_bytes),
        min(_U16, c.setpoints_refused), 0)


def _gps_raw(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    """The GNSS receiver: the latest position sample, as an RTK fix of the given accuracy."""
    m, i = v.measurements, v.index
    usec = int(v.t * 1e6)
    if m.pose_seq[i] == 0:
        return mav.gps_raw_int_encode(usec, mavlink.GPS_FIX_TYPE_NO_FIX, 0, 0, 0, _U16, _U16,
                                      _U16, _U16, 0)
    lat, lon, alt = v.geodetic(m.p_ned[i])
    vn, ve = float(m.v_ned[i, 0]), float(m.v_ned[i, 1])
    speed = math.hypot(vn, ve)
    cog = round(math.degrees(math.atan2(ve, vn)) * 100.0) % 36000 if speed > 0.05 else _U16
    acc_cm = max(1, round(v.identity.gps_accuracy_m * 100.0))
    acc_mm = max(1, round(v.identity.gps_accuracy_m * 1000.0))
    return mav.gps_raw_int_encode(
        usec, mavlink.GPS_FIX_TYPE_RTK_FIXED, _deg_e7(lat), _deg_e7(lon), _mm(alt), acc_cm,
        acc_cm, min(_U16 - 1, round(speed * 100.0)), cog, _GPS_SATELLITES, _mm(alt), acc_mm,
        acc_mm, 10, 0, 0)


def _global_position(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage | None:
    """The estimate as a global position (what PX4 derives from its EKF and origin)."""
    if not v.located:
        return None
    s, i = v.autopilot.state, v.index
    lat, lon, alt = v.geodetic(s.p_est[i] + s.origin_ned[i])
    relative = alt - v.home.geodetic.alt_m if v.home is not None else 0.0
    q = s.q_est[i]
    yaw = quat_to_euler(float(q[0]), float(q[1]), float(q[2]), float(q[3]))[2]
    return mav.global_position_int_encode(
        time_boot_ms(v.t), _deg_e7(lat), _deg_e7(lon), _mm(alt), _mm(relative),
        *(_cm_s(float(x)) for x in s.v_est[i]), round(math.degrees(yaw) * 100.0) % 36000)


def _home_position(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage | None:
    """Home: where the vehicle was when it last armed (until then, where it started)."""
    if v.home is None:
        return None
    lat, lon, alt = v.home.geodetic
    local = v.home.ned - v.autopilot.state.origin_ned[v.index]
    return mav.home_position_encode(_deg_e7(lat), _deg_e7(lon), _mm(alt),
                                    *(float(x) for x in local), [1.0, 0.0, 0.0, 0.0],
                                    0.0, 0.0, 0.0, int(v.t * 1e6))


def _gps_global_origin(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    """The local frame's origin (PX4's EKF origin; SET_GPS_GLOBAL_ORIGIN moves it)."""
    lat, lon, alt = v.origin()
    return mav.gps_global_origin_encode(_deg_e7(lat), _deg_e7(lon), _mm(alt), int(v.t * 1e6))


def _autopilot_version(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    return mav.autopilot_version_encode(
        CAPABILITIES, FLIGHT_SW_VERSION, 0, 0, 0, _CUSTOM_VERSION, bytes(8), bytes(8), 0, 0,
        v.identity.sysid, bytes(18))


def _deg_e7(degrees: float) -> int:
    return round(degrees * 1e7)


def _mm(metres: float) -> int:
    return round(metres * 1000.0)


def _cm_s(speed: float) -> int:
    return max(-32767, min(32767, round(speed * 100.0)))


def time_boot_ms(t: float) -> int:
    """``time_boot_ms`` field for sim time ``t`` (s since the run started)."""
    return int(t * 1000.0) & 0xFFFFFFFF


_BUILDERS: dict[TelemetryMessage, Callable[[mavlink.MAVLink, VehicleView], MavMessage | None]] = {
    TelemetryMessage.HEARTBEAT: _heartbeat,
    TelemetryMessage.LOCAL_POSITION_NED: _position,
    TelemetryMessage.ATTITUDE: _attitude,
    TelemetryMessage.ATTITUDE_QUATERNION: _attitude_quaternion,
    TelemetryMessage.ATTITUDE_TARGET: _attitude_target,
    TelemetryMessage.HIGHRES_IMU: _imu,
    TelemetryMessage.SYS_STATUS: _sys_status,
    TelemetryMessage.GPS_RAW_INT: _gps_raw,
    TelemetryMessage.GLOBAL_POSITION_INT: _global_position,
    TelemetryMessage.HOME_POSITION: _home_position,
    TelemetryMessage.GPS_GLOBAL_ORIGIN: _gps_global_origin,
    TelemetryMessage.AUTOPILOT_VERSION: _autopilot_version,
}
