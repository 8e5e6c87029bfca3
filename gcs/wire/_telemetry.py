"""Latest telemetry of one vehicle, kept as immutable records.

The receiving thread replaces a record whenever a message arrives; the GCS
loop takes a :class:`Telemetry` snapshot, which is a consistent set of
references that later messages cannot change under it. Frames: NED
navigation frame, FRD body frame, SI units, radians.

A message whose values the GCS reads are not finite, or beyond
:data:`TELEMETRY_MAX_ABS`, is refused and counted
(:attr:`TelemetryStore.refused`), never stored: an ATTITUDE with infinite
angles raised "math domain error" on the receive thread, a traceback per
message, and a vehicle "at" 1e38 m is no position the loop can fly by.
"""

from __future__ import annotations

import math
import re
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum

from gcs.wire._dialect import MavMessage
from gcs.wire._modes import SAFETY_ARMED

__all__ = [
    "OFFBOARD_LOST_TEXT",
    "TELEMETRY_MAX_ABS",
    "Attitude",
    "Heartbeat",
    "Imu",
    "LocalPosition",
    "Severity",
    "StatusText",
    "SystemStatus",
    "Telemetry",
    "TelemetryRecord",
    "TelemetryStore",
    "ThrustTarget",
]

Vec3 = tuple[float, float, float]

TELEMETRY_MAX_ABS = 1e6
"""Largest magnitude of a telemetry value taken (m, m/s, m/s^2, rad, rad/s): beyond any
flight of a team (a local frame of 1000 km), and far below what overflows a square."""


class Severity(IntEnum):
    """``MAV_SEVERITY`` of a status text."""

    EMERGENCY = 0
    ALERT = 1
    CRITICAL = 2
    ERROR = 3
    WARNING = 4
    NOTICE = 5
    INFO = 6
    DEBUG = 7

    @property
    def text(self) -> str:
        """Lower-case label for logs and the UI."""
        return self.name.lower()


@dataclass(frozen=True, slots=True)
class Heartbeat:
    """Latest ``HEARTBEAT`` of the vehicle's autopilot component."""

    armed: bool
    base_mode: int
    custom_mode: int
    """Autopilot-specific mode number (see :mod:`gcs.wire._modes`)."""
    system_status: int
    """``MAV_STATE`` value."""
    autopilot: int
    """``MAV_AUTOPILOT`` value."""
    vehicle_type: int
    """``MAV_TYPE`` value."""
    received_at: float
    """Link clock time of arrival, s."""


@dataclass(frozen=True, slots=True)
class LocalPosition:
    """Latest ``LOCAL_POSITION_NED``."""

    p_ned: Vec3
    """Position, m."""
    v_ned: Vec3
    """Velocity, m/s."""
    time_boot_s: float
    """Vehicle's time stamp, s."""
    received_at: float


@dataclass(frozen=True, slots=True)
class Attitude:
    """Latest ``ATTITUDE`` or ``ATTITUDE_QUATERNION`` (both forms always filled)."""

    q_wxyz: tuple[float, float, float, float]
    """Rotation from body FRD to NED, scalar first."""
    rpy: Vec3
    """Roll, pitch, yaw (ZYX Euler), rad."""
    rates_body: Vec3
    """Body angular rates p, q, r, rad/s."""
    time_boot_s: float
    received_at: float


@dataclass(frozen=True, slots=True)
class ThrustTarget:
    """Latest collective thrust of ``ATTITUDE_TARGET``: what the vehicle's attitude
    controller asks of its rotors (PX4 and ArduCopter send it), read for the rope's load."""

    thrust: float
    """Collective thrust, normalised 0 .. 1 of the autopilot's own scale (-1 .. 0: reverse
    thrust, or a copter spooling down on the ground)."""
    received_at: float


@dataclass(frozen=True, slots=True)
class Imu:
    """Latest ``HIGHRES_IMU``."""

    accel_body: Vec3
    """Specific force in body FRD, m/s^2 (about (0, 0, -9.81) at rest)."""
    gyro_body: Vec3
    """Angular rate in body FRD, rad/s."""
    time_s: float
    """Vehicle's time stamp, s."""
    received_at: float


@dataclass(frozen=True, slots=True)
class SystemStatus:
    """Latest ``SYS_STATUS``."""

    battery_voltage_v: float | None
    battery_current_a: float | None
    battery_remaining_pct: int | None
    load_pct: float
    """Main loop load, %."""
    drop_rate_comm_pct: float
    """Vehicle-side communication drop rate, %."""
    sensors_healthy: bool
    """True if every enabled sensor reports healthy."""
    received_at: float


@dataclass(frozen=True, slots=True)
class StatusText:
    """One ``STATUSTEXT`` line."""

    severity: Severity
    text: str
    received_at: float

    @property
    def setpoints_lost(self) -> bool:
        """Whether the autopilot says it left offboard because the setpoints stopped (our
        simulated vehicle's :data:`OFFBOARD_LOST_TEXT`, PX4's offboard-loss failsafe)."""
        return _SETPOINTS_LOST.search(self.text) is not None


OFFBOARD_LOST_TEXT = "Failsafe: offboard setpoints lost, holding"
"""What a simulated vehicle says when its setpoint timeout sends it from OFFBOARD to HOLD."""

_SETPOINTS_LOST = re.compile(r"offboard.*(lost|loss|signal|timeout)|setpoints? (lost|timeout)",
                             re.IGNORECASE)


TelemetryRecord = (Heartbeat | LocalPosition | Attitude | Imu | SystemStatus | StatusText
                   | ThrustTarget)
"""Any one telemetry record."""


@dataclass(frozen=True, slots=True)
class Telemetry:
    """Consistent snapshot of a vehicle's latest telemetry; None where nothing arrived yet."""

    sysid: int
    heartbeat: Heartbeat | None
    position: LocalPosition | None
    attitude: Attitude | None
    imu: Imu | None
    status: SystemStatus | None
    status_texts: tuple[StatusText, ...]
    """Most recent status texts, oldest first."""
    thrust: ThrustTarget | None = None


class TelemetryStore:
    """Keeps the latest record of each kind; callers serialise access (the Link's lock)."""

    def __init__(self, sysid: int, *, status_text_history: int = 20) -> None:
        self.sysid = sysid
        self.heartbeat: Heartbeat | None = None
        self.position: LocalPosition | None = None
        self.attitude: Attitude | None = None
        self.imu: Imu | None = None
        self.status: SystemStatus | None = None
        self.thrust: ThrustTarget | None = None
        self._texts: deque[StatusText] = deque(maxlen=status_text_history)
        self.refused = 0
        """Telemetry messages refused: a value not finite or beyond :data:`TELEMETRY_MAX_ABS`."""
        self._handlers: dict[str, Callable[[MavMessage, float], TelemetryRecord | None]] = {
            "HEARTBEAT": self._heartbeat,
            "LOCAL_POSITION_NED": self._position,
            "ATTITUDE": self._attitude,
            "ATTITUDE_QUATERNION": self._attitude_quaternion,
            "HIGHRES_IMU": self._imu,
            "SYS_STATUS": self._sys_status,
            "STATUSTEXT": self._status_text,
            "ATTITUDE_TARGET": self._thrust,
        }

    def update(self, msg: MavMessage, now: float) -> TelemetryRecord | None:
        """Take ``msg`` if it is telemetry; the new record, or None if ``msg`` is not one or
        was refused (counted in :attr:`refused`)."""
        handler = self._handlers.get(msg.get_type())
        if handler is None:
            return None
        record = handler(msg, now)
        if record is None:
            self.refused += 1
        return record

    def snapshot(self) -> Telemetry:
        """The current records as one immutable snapshot."""
        return Telemetry(self.sysid, self.heartbeat, self.position, self.attitude, self.imu,
                         self.status, tuple(self._texts), self.thrust)

    def _heartbeat(self, m: MavMessage, now: float) -> Heartbeat:
        self.heartbeat = Heartbeat(bool(m.base_mode & SAFETY_ARMED), m.base_mode, m.custom_mode,
                                   m.system_status, m.autopilot, m.type, now)
        return self.heartbeat

    def _position(self, m: MavMessage, now: float) -> LocalPosition | None:
        p, v = (m.x, m.y, m.z), (m.vx, m.vy, m.vz)
        if not _usable(*p, *v):
            return None
        self.position = LocalPosition(p, v, m.time_boot_ms / 1000.0, now)
        return self.position

    def _attitude(self, m: MavMessage, now: float) -> Attitude | None:
        rpy, rates = (m.roll, m.pitch, m.yaw), (m.rollspeed, m.pitchspeed, m.yawspeed)
        if not _usable(*rpy, *rates):
            return None
        self.attitude = Attitude(_quaternion_from_rpy(rpy), rpy, rates,
                                 m.time_boot_ms / 1000.0, now)
        return self.attitude

    def _attitude_quaternion(self, m: MavMessage, now: float) -> Attitude | None:
        q, rates = (m.q1, m.q2, m.q3, m.q4), (m.rollspeed, m.pitchspeed, m.yawspeed)
        if not _usable(*q, *rates):
            return None
        self.attitude = Attitude(q, _rpy_from_quaternion(q), rates,
                                 m.time_boot_ms / 1000.0, now)
        return self.attitude

    def _thrust(self, m: MavMessage, now: float) -> ThrustTarget | None:
        """A thrust outside MAVLink's -1 .. 1 (reverse thrust below 0; ArduCopter reports
        down to -0.17 while it touches down), or one the sender marks as ignored (type_mask
        bit 6), is none."""
        if m.type_mask & _THRUST_IGNORED or not -1.0 <= m.thrust <= 1.0:
            return None
        self.thrust = ThrustTarget(float(m.thrust), now)
        return self.thrust

    def _imu(self, m: MavMessage, now: float) -> Imu | None:
        accel, gyro = (m.xacc, m.yacc, m.zacc), (m.xgyro, m.ygyro, m.zgyro)
        if not _usable(*accel, *gyro):
            return None
        self.imu = Imu(accel, gyro, m.time_usec / 1e6, now)
        return self.imu

    def _sys_status(self, m: MavMessage, now: float) -> SystemStatus:
        enabled = m.onboard_control_sensors_enabled
        self.status = SystemStatus(
            battery_voltage_v=m.voltage_battery / 1000.0 if m.voltage_battery != 0xFFFF else None,
            battery_current_a=m.current_battery / 100.0 if m.current_battery >= 0 else None,
            battery_remaining_pct=m.battery_remaining if m.battery_remaining >= 0 else None,
            load_pct=m.load / 10.0,
            drop_rate_comm_pct=m.drop_rate_comm / 100.0,
            sensors_healthy=(m.onboard_control_sensors_health & enabled) == enabled,
            received_at=now)
        return self.status

    def _status_text(self, m: MavMessage, now: float) -> StatusText:
        text = m.text if isinstance(m.text, str) else m.text.decode("utf-8", "replace")
        try:
            severity = Severity(m.severity)
        except ValueError:
            severity = Severity.DEBUG
        record = StatusText(severity, text, now)
        self._texts.append(record)
        return record


_THRUST_IGNORED = 64
"""``ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE``."""


def _usable(*values: float) -> bool:
    """Whether every value is finite and within :data:`TELEMETRY_MAX_ABS` (NaN is not)."""
    return all(-TELEMETRY_MAX_ABS <= x <= TELEMETRY_MAX_ABS for x in values)


def _quaternion_from_rpy(rpy: Vec3) -> tuple[float, float, float, float]:
    cr, sr = math.cos(rpy[0] / 2), math.sin(rpy[0] / 2)
    cp, sp = math.cos(rpy[1] / 2), math.sin(rpy[1] / 2)
    cy, sy = math.cos(rpy[2] / 2), math.sin(rpy[2] / 2)
    return (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy)


def _rpy_from_quaternion(q: tuple[float, float, float, float]) -> Vec3:
    w, x, y, z = q
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return (roll, pitch, yaw)

