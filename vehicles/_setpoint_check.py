"""Input checks on SET_POSITION_TARGET_LOCAL_NED before a setpoint may reach the autopilot.

Why: a setpoint that is flown cannot be taken back. The vehicle takes only
what PX4 and ArduPilot take for acceleration control: acceleration on all
three axes, or x/y acceleration with a z position (``MAV_FRAME_LOCAL_NED``,
``FORCE_SET`` ignored, yaw fields ignored as by :func:`gcs.wire.read_setpoint`).
Anything else (another type mask or frame, NaN or infinity, values outside
:class:`SetpointLimits`) is refused with a :class:`Refusal` the endpoint
reports by STATUSTEXT.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

from gcs.wire import AccelSetpoint, MavMessage, SetpointKind, TypeMask, mavlink, read_setpoint

__all__ = ["Refusal", "SetpointLimits", "SetpointVerdict", "check_setpoint"]


@dataclass(frozen=True)
class SetpointLimits:
    """Largest values a setpoint may carry; beyond them it is refused, not clipped."""

    accel_max: float = 10.0
    """Largest acceleration on any axis, m/s^2 (about 45 degrees of bank)."""
    z_max: float = 100.0
    """Largest |z| position, m from the local origin."""


class Refusal(Enum):
    """Why a setpoint was refused; the value is the operator-facing reason."""

    FRAME = "frame is not LOCAL_NED"
    TYPE_MASK = "type_mask is not accel or accel_xy+z"
    NOT_FINITE = "NaN or infinite value"
    OUT_OF_RANGE = "value out of range"


@dataclass(frozen=True)
class SetpointVerdict:
    """An accepted setpoint, or the reason it was refused and the offending value."""

    setpoint: AccelSetpoint | None
    refusal: Refusal | None = None
    detail: str = ""
    """The offending value, e.g. ``"type_mask 3583"`` (fits one STATUSTEXT with the prefix)."""

    @property
    def text(self) -> str:
        """One STATUSTEXT line of at most 50 characters."""
        if self.refusal is None:
            return "setpoint accepted"
        return f"setpoint refused: {self.detail}"


def check_setpoint(msg: MavMessage, limits: SetpointLimits) -> SetpointVerdict:
    """Judge one SET_POSITION_TARGET_LOCAL_NED message (addressing is the caller's job)."""
    if msg.coordinate_frame != mavlink.MAV_FRAME_LOCAL_NED:
        return SetpointVerdict(None, Refusal.FRAME,
                               f"frame {msg.coordinate_frame} not LOCAL_NED")
    setpoint = read_setpoint(msg)
    if setpoint is None:
        mask = msg.type_mask & ~int(TypeMask.FORCE_SET)
        return SetpointVerdict(None, Refusal.TYPE_MASK, f"type_mask {mask} unsupported")
    accel: tuple[float, ...]
    values: tuple[float, ...]
    if setpoint.kind is SetpointKind.ACCEL:
        accel = setpoint.accel_ned
        values = accel
    else:
        assert setpoint.z_ned is not None  # read_setpoint gives ACCEL_XY_POS_Z its z
        accel = setpoint.accel_ned[:2]
        values = (*accel, float(setpoint.z_ned))
    if not all(math.isfinite(v) for v in values):
        return SetpointVerdict(None, Refusal.NOT_FINITE, "NaN or infinite value")
    worst = max(abs(a) for a in accel)
    if worst > limits.accel_max:
        return SetpointVerdict(None, Refusal.OUT_OF_RANGE,
                               f"accel {worst:.3g} > {limits.accel_max:g} m/s^2")
    if setpoint.z_ned is not None and abs(setpoint.z_ned) > limits.z_max:
        return SetpointVerdict(None, Refusal.OUT_OF_RANGE,
                               f"|z| {abs(setpoint.z_ned):.3g} > {limits.z_max:g} m")
    return SetpointVerdict(setpoint)
