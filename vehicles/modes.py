"""Flight modes, setpoint kinds and command results of the onboard autopilot.

The numeric kernel stores modes and setpoint kinds as small integers (numba
arrays); these enums give them names and human-readable text for telemetry,
logs and the later COMMAND_ACK mapping.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum, IntEnum

__all__ = ["CommandResult", "Denial", "Mode", "SetpointKind"]


class Mode(IntEnum):
    """Flight mode of one vehicle; the value is what the kernel stores.

    Values match ``gcs.link.modes.SimMode`` (HEARTBEAT.custom_mode) where the
    names match; DISARMED is reported there as IDLE. 0 is unused so a zeroed
    field never reads as a mode.
    """

    DISARMED = 1
    TAKEOFF = 2
    HOLD = 3
    OFFBOARD = 4
    LAND = 5

    @property
    def text(self) -> str:
        """One-line description for operators."""
        return _MODE_TEXT[self]


_MODE_TEXT = {
    Mode.DISARMED: "disarmed, rotors stopped",
    Mode.TAKEOFF: "taking off to the commanded altitude",
    Mode.HOLD: "holding position where the hold started (idling if that is on the ground)",
    Mode.OFFBOARD: "tracking external acceleration setpoints",
    Mode.LAND: "landing, disarms on touchdown",
}


class SetpointKind(IntEnum):
    """What an external setpoint commands (later: SET_POSITION_TARGET_LOCAL_NED type_mask)."""

    NONE = 0
    ACCEL = 1
    ACCEL_XY_POS_Z = 2

    @property
    def text(self) -> str:
        """One-line description for operators."""
        return _SETPOINT_TEXT[self]


_SETPOINT_TEXT = {
    SetpointKind.NONE: "no setpoint received",
    SetpointKind.ACCEL: "x/y/z acceleration (NED)",
    SetpointKind.ACCEL_XY_POS_Z: "x/y acceleration with altitude held at a z position (NED)",
}


class Denial(Enum):
    """Why a command was refused; the value is the operator-facing text."""

    DISARMED = "vehicle is disarmed"
    IN_FLIGHT = "vehicle is in flight"
    NO_POSE = "no position measurement received yet"
    NO_SETPOINT_STREAM = "no setpoint received within the setpoint timeout"
    BAD_ALTITUDE = "takeoff altitude must exceed the ground clearance"


@dataclass(frozen=True)
class CommandResult:
    """Outcome of a mode or arming request (later sent as COMMAND_ACK)."""

    accepted: bool
    denial: Denial | None = None

    def __post_init__(self) -> None:
        if self.accepted == (self.denial is not None):
            raise ValueError("a command result has a denial reason exactly when it is denied")

    @property
    def text(self) -> str:
        """``"accepted"`` or ``"denied: <reason>"``."""
        if self.accepted:
            return "accepted"
        return f"denied: {self.denial.value}"  # type: ignore[union-attr]
