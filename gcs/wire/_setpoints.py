"""Acceleration setpoints as ``SET_POSITION_TARGET_LOCAL_NED`` (frame LOCAL_NED).

Two channel sets are used, both accepted by the autopilots' input checks:

- :data:`MASK_ACCEL_XY_POS_Z`: x/y acceleration and z position. PX4 offboard
  and the simulated vehicles (their altitude loop holds z).
- :data:`MASK_ACCEL`: acceleration on all three axes. ArduCopter GUIDED takes
  acceleration only as a whole group (all three axes or none), so the GCS
  closes the vertical loop itself and sends ``afz``.

Yaw and yaw rate are ignored in both: the formation does not steer heading.
:func:`read_setpoint` is the receiving side's reading of the same message.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum, IntFlag

import numpy as np

from gcs.common import kernel
from gcs.wire._dialect import MavMessage, mavlink
from gcs.wire._encoder import frame_dtype, packed_rows

__all__ = [
    "MASK_ACCEL",
    "MASK_ACCEL_XY_POS_Z",
    "SETPOINT_MESSAGE",
    "AccelSetpoint",
    "SetpointKind",
    "SetpointPacker",
    "TypeMask",
    "accel_setpoint_fields",
    "accel_setpoint_message",
    "packed_setpoints",
    "read_setpoint",
]

SETPOINT_MESSAGE = mavlink.MAVLink_set_position_target_local_ned_message
"""The pymavlink class of ``SET_POSITION_TARGET_LOCAL_NED``."""


class TypeMask(IntFlag):
    """``POSITION_TARGET_TYPEMASK`` bits: a set bit means "ignore this field"."""

    X_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_X_IGNORE
    Y_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_Y_IGNORE
    Z_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_Z_IGNORE
    VX_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_VX_IGNORE
    VY_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_VY_IGNORE
    VZ_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_VZ_IGNORE
    AX_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_AX_IGNORE
    AY_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_AY_IGNORE
    AZ_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_AZ_IGNORE
    FORCE_SET = mavlink.POSITION_TARGET_TYPEMASK_FORCE_SET
    YAW_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_YAW_IGNORE
    YAW_RATE_IGNORE = mavlink.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE


_POS = TypeMask.X_IGNORE | TypeMask.Y_IGNORE | TypeMask.Z_IGNORE
_VEL = TypeMask.VX_IGNORE | TypeMask.VY_IGNORE | TypeMask.VZ_IGNORE
_YAW = TypeMask.YAW_IGNORE | TypeMask.YAW_RATE_IGNORE

MASK_ACCEL = int(_POS | _VEL | _YAW)
"""Acceleration on x, y, z only (3135)."""

MASK_ACCEL_XY_POS_Z = int(TypeMask.X_IGNORE | TypeMask.Y_IGNORE | _VEL | TypeMask.AZ_IGNORE | _YAW)
"""x/y acceleration plus z position (3387)."""


class SetpointKind(IntEnum):
    """Which channels an acceleration setpoint carries; the value is what the
    simulated autopilot's kernel stores."""

    NONE = 0
    ACCEL = 1
    ACCEL_XY_POS_Z = 2

    @property
    def text(self) -> str:
        """One-line description for operators."""
        return _SETPOINT_TEXT[self]

    @property
    def type_mask(self) -> int:
        """The ``type_mask`` that selects these channels (there is none for NONE)."""
        if self is SetpointKind.NONE:
            raise ValueError("no setpoint has no type_mask")
        return MASK_ACCEL if self is SetpointKind.ACCEL else MASK_ACCEL_XY_POS_Z


_SETPOINT_TEXT = {
    SetpointKind.NONE: "no setpoint received",
    SetpointKind.ACCEL: "x/y/z acceleration (NED)",
    SetpointKind.ACCEL_XY_POS_Z: "x/y acceleration with altitude held at a z position (NED)",
}


@dataclass(frozen=True)
class AccelSetpoint:
    """An acceleration setpoint as the vehicle reads it (NED, SI units)."""

    kind: SetpointKind
    accel_ned: tuple[float, float, float]
    """Commanded acceleration, m/s^2; z is NaN for ``ACCEL_XY_POS_Z``."""
    z_ned: float | None
    """Commanded z position (down), m; None for ``ACCEL``."""
    time_boot_ms: int
    """Sender's time stamp, ms."""


def accel_setpoint_fields(*, target_system: int, target_component: int, time_boot_ms: int,
                          accel_xy_ned: tuple[float, float], z_ned: float | None = None,
                          az_ned: float | None = None) -> tuple[float, ...]:
    """``SET_POSITION_TARGET_LOCAL_NED`` with x/y acceleration and exactly one vertical channel.

    ``z_ned`` (m, down) selects :data:`MASK_ACCEL_XY_POS_Z`; ``az_ned`` (m/s^2,
    down, gravity excluded) selects :data:`MASK_ACCEL`. Returns the field values
    in wire order (``SETPOINT_MESSAGE.ordered_fieldnames``), for
    :meth:`gcs.wire.MavlinkEncoder.encode_fields`.
    """
    if (z_ned is None) == (az_ned is None):
        raise ValueError("give exactly one vertical channel: z_ned or az_ned")
    ax, ay = float(accel_xy_ned[0]), float(accel_xy_ned[1])
    vertical = float(z_ned if z_ned is not None else az_ned)  # type: ignore[arg-type]
    if not (math.isfinite(ax) and math.isfinite(ay) and math.isfinite(vertical)):
        raise ValueError(f"setpoint must be finite, got a=({ax}, {ay}) vertical={vertical}")
    if z_ned is not None:
        mask, z, az = MASK_ACCEL_XY_POS_Z, vertical, 0.0
    else:
        mask, z, az = MASK_ACCEL, 0.0, vertical
    return (time_boot_ms & 0xFFFFFFFF, 0.0, 0.0, z, 0.0, 0.0, 0.0, ax, ay, az, 0.0, 0.0, mask,
            target_system, target_component, mavlink.MAV_FRAME_LOCAL_NED)


def packed_setpoints(*, target_system: np.ndarray, target_component: np.ndarray,
                     time_boot_ms: np.ndarray, accel_xy_ned: np.ndarray, vertical: np.ndarray,
                     kind: np.ndarray) -> np.ndarray:
    """A fleet's setpoints packed at once, one per row (:func:`~gcs.wire._encoder.packed_rows`),
    for :class:`~gcs.link.Fanout`.

    Per vehicle: ``accel_xy_ned`` (n, 2) m/s^2, ``vertical`` (n,) the z (m, down)
    or the down acceleration (m/s^2) as the ``kind`` (n,) type mask says
    (:data:`MASK_ACCEL_XY_POS_Z` or :data:`MASK_ACCEL`). Values must be finite
    (the caller checks: a refused row must not reach the vehicle at all).
    """
    z_channel = kind == MASK_ACCEL_XY_POS_Z
    return packed_rows(SETPOINT_MESSAGE, len(kind), {
        "time_boot_ms": time_boot_ms, "z": np.where(z_channel, vertical, 0.0),
        "afx": accel_xy_ned[:, 0], "afy": accel_xy_ned[:, 1],
        "afz": np.where(z_channel, 0.0, vertical), "type_mask": kind,
        "target_system": target_system, "target_component": target_component,
        "coordinate_frame": mavlink.MAV_FRAME_LOCAL_NED})


class SetpointPacker:
    """A fixed fleet's setpoints packed at once in one compiled pass, per tick.

    The constant fields (targets, type masks, frame) are packed once here; each
    :meth:`pack` writes the time stamps and the acceleration and vertical
    channels into a copy. Why: :func:`packed_setpoints` takes about fifteen
    numpy calls, and after the loop's pause between ticks each pays again for
    the caches that were evicted meanwhile (figures: docs/performance.md,
    bench/gcs_tick.py). Rows as :func:`packed_setpoints` gives them.
    """

    def __init__(self, *, target_system: np.ndarray, target_component: np.ndarray,
                 kind: np.ndarray, boot_time: np.ndarray) -> None:
        n = len(kind)
        self._template = packed_setpoints(
            target_system=target_system, target_component=target_component,
            time_boot_ms=np.zeros(n, np.int64), accel_xy_ned=np.zeros((n, 2)),
            vertical=np.zeros(n), kind=kind)
        self._z_channel = np.asarray(kind) == MASK_ACCEL_XY_POS_Z
        self._boot_time = np.asarray(boot_time, dtype=float)
        self.pack(0.0, np.zeros((n, 2)), np.zeros(n))  # compile or load the kernel now

    def pack(self, now: float, accel_xy_ned: np.ndarray, vertical: np.ndarray) -> np.ndarray:
        """Rows for monotonic time ``now`` (s; ``time_boot_ms`` counts from each vehicle's
        ``boot_time``), ``accel_xy_ned`` (n, 2) and ``vertical`` (n,) (z or az by kind)."""
        return _pack(self._template, self._z_channel, self._boot_time, now,
                     np.asarray(accel_xy_ned, dtype=float), np.asarray(vertical, dtype=float),
                     _OFFSETS)


_SETPOINT_FIELDS = frame_dtype(SETPOINT_MESSAGE).fields
assert _SETPOINT_FIELDS is not None  # a packed frame's dtype is structured: named fields
_OFFSETS = np.array([_SETPOINT_FIELDS[name][1]
                     for name in ("time_boot_ms", "z", "afx", "afy", "afz")], np.int64)
"""Byte offsets in a packed row of the fields that change from tick to tick (an argument
of the kernel, not a constant compiled into its cache)."""


@kernel()
def _pack(template: np.ndarray, z_channel: np.ndarray, boot_time: np.ndarray, now: float,
          accel: np.ndarray, vertical: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    t_ms, z, afx, afy, afz = offsets[0], offsets[1], offsets[2], offsets[3], offsets[4]
    out = template.copy()
    f32 = np.empty(1, np.float32)
    f32_bytes = f32.view(np.uint8)
    u32 = np.empty(1, np.uint32)
    u32_bytes = u32.view(np.uint8)
    for i in range(out.shape[0]):
        u32[0] = np.uint32(np.int64((now - boot_time[i]) * 1000.0) & 0xFFFFFFFF)
        out[i, t_ms:t_ms + 4] = u32_bytes
        for offset, value in ((afx, accel[i, 0]), (afy, accel[i, 1]),
                              (z if z_channel[i] else afz, vertical[i])):
            f32[0] = value
            out[i, offset:offset + 4] = f32_bytes
    return out


def accel_setpoint_message(*, target_system: int, target_component: int, time_boot_ms: int,
                           accel_xy_ned: tuple[float, float], z_ned: float | None = None,
                           az_ned: float | None = None) -> MavMessage:
    """The message of :func:`accel_setpoint_fields` as a pymavlink object."""
    values = accel_setpoint_fields(target_system=target_system,
                                   target_component=target_component,
                                   time_boot_ms=time_boot_ms, accel_xy_ned=accel_xy_ned,
                                   z_ned=z_ned, az_ned=az_ned)
    return SETPOINT_MESSAGE(**dict(zip(SETPOINT_MESSAGE.ordered_fieldnames, values,
                                       strict=True)))


def read_setpoint(msg: MavMessage) -> AccelSetpoint | None:
    """The acceleration setpoint in ``msg``, or None if it is not one of the two kinds above.

    Only ``SET_POSITION_TARGET_LOCAL_NED`` in ``MAV_FRAME_LOCAL_NED`` qualifies; the
    ``FORCE_SET`` bit is ignored.
    """
    if msg.get_type() != "SET_POSITION_TARGET_LOCAL_NED":
        return None
    if msg.coordinate_frame != mavlink.MAV_FRAME_LOCAL_NED:
        return None
    mask = msg.type_mask & ~int(TypeMask.FORCE_SET)
    if mask == MASK_ACCEL:
        return AccelSetpoint(SetpointKind.ACCEL, (msg.afx, msg.afy, msg.afz), None,
                             msg.time_boot_ms)
    if mask == MASK_ACCEL_XY_POS_Z:
        return AccelSetpoint(SetpointKind.ACCEL_XY_POS_Z, (msg.afx, msg.afy, math.nan), msg.z,
                             msg.time_boot_ms)
    return None
