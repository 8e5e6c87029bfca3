"""Telemetry messages of one simulated vehicle, built from its autopilot's own state.

Why: the GCS must see a simulated vehicle exactly as it sees a real one, so
each message reports what an onboard autopilot knows (its position and
attitude estimates, its IMU, its battery monitor), never the simulator's
truth. Times are sim time since the start of the run (``time_boot``).
"""

from __future__ import annotations

from dataclasses import dataclass

from gcs.wire import CUSTOM_MODE_ENABLED, SAFETY_ARMED, MavMessage, SimMode, mavlink
from vehicles._autopilot import Autopilot
from vehicles._battery import BatteryReading
from vehicles._quaternion import quat_to_euler
from vehicles._state import Measurements
from vehicles._streams import TelemetryMessage

__all__ = [
    "LOW_BATTERY",
    "CommCounters",
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


def build_report(mav: mavlink.MAVLink, message: TelemetryMessage, view: VehicleView) -> MavMessage:
    """The ``message`` the vehicle sends now."""
    return _BUILDERS[message](mav, view)


def _heartbeat(mav: mavlink.MAVLink, v: VehicleView) -> MavMessage:
    mode = v.autopilot.mode(v.index)
    armed = mode is not SimMode.DISARMED
    if v.battery.remaining < LOW_BATTERY:
        state = mavlink.MAV_STATE_CRITICAL
    else:
        state = mavlink.MAV_STATE_ACTIVE if armed else mavlink.MAV_STATE_STANDBY
    return mav.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_GENERIC,
                                CUSTOM_MODE_ENABLED | (SAFETY_ARMED if armed else 0),
                                int(mode), state)


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


def time_boot_ms(t: float) -> int:
    """``time_boot_ms`` field for sim time ``t`` (s since the run started)."""
    return int(t * 1000.0) & 0xFFFFFFFF


_BUILDERS = {
    TelemetryMessage.HEARTBEAT: _heartbeat,
    TelemetryMessage.LOCAL_POSITION_NED: _position,
    TelemetryMessage.ATTITUDE: _attitude,
    TelemetryMessage.ATTITUDE_QUATERNION: _attitude_quaternion,
    TelemetryMessage.HIGHRES_IMU: _imu,
    TelemetryMessage.SYS_STATUS: _sys_status,
}
