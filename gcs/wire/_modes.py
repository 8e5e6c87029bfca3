"""Flight-mode numbers of every autopilot the GCS drives, in one place.

MAVLink leaves the meaning of ``HEARTBEAT.custom_mode`` and of
``MAV_CMD_DO_SET_MODE`` param2/param3 to each autopilot. The simulated
vehicles' numbers are *defined* here (the sim imports them); PX4's and
ArduCopter's are copied from their sources (PX4 ``px4_custom_mode.h``,
ArduCopter ``mode.h``).

Simulated vehicles send ``HEARTBEAT`` with type ``MAV_TYPE_QUADROTOR``,
autopilot ``MAV_AUTOPILOT_GENERIC``, ``base_mode`` with
``MAV_MODE_FLAG_CUSTOM_MODE_ENABLED`` (plus ``MAV_MODE_FLAG_SAFETY_ARMED`` when
armed) and ``custom_mode`` = a :class:`SimMode` value. A mode change is
``MAV_CMD_DO_SET_MODE`` with param1 = ``MAV_MODE_FLAG_CUSTOM_MODE_ENABLED`` and
param2 = the :class:`SimMode` value.
"""

from __future__ import annotations

from enum import IntEnum

from gcs.wire._dialect import mavlink

__all__ = [
    "CUSTOM_MODE_ENABLED",
    "SAFETY_ARMED",
    "CopterMode",
    "Px4AutoSubMode",
    "Px4MainMode",
    "SimMode",
    "copter_mode_text",
    "heartbeat_mode_text",
    "px4_custom_mode",
    "px4_mode_text",
    "sim_mode_text",
    "split_px4_custom_mode",
]

CUSTOM_MODE_ENABLED = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
"""``base_mode`` bit saying ``custom_mode`` is meaningful; DO_SET_MODE param1."""

SAFETY_ARMED = mavlink.MAV_MODE_FLAG_SAFETY_ARMED
"""``base_mode`` bit set while the motors are armed."""


class SimMode(IntEnum):
    """Flight mode of a simulated vehicle: what its autopilot kernel stores and what
    its ``HEARTBEAT.custom_mode`` says.

    0 is deliberately unused so that a missing or zeroed field never reads as
    a real mode.
    """

    DISARMED = 1
    TAKEOFF = 2
    HOLD = 3
    OFFBOARD = 4
    LAND = 5

    @property
    def text(self) -> str:
        """What the vehicle does in this mode."""
        return _SIM_TEXT[self]


_SIM_TEXT = {
    SimMode.DISARMED: "disarmed, rotors stopped",
    SimMode.TAKEOFF: "taking off to the commanded altitude",
    SimMode.HOLD: "holding position where the hold started (idling if that is on the ground)",
    SimMode.OFFBOARD: "tracking external acceleration setpoints",
    SimMode.LAND: "landing, disarms on touchdown",
}


class Px4MainMode(IntEnum):
    """PX4 custom main modes (``custom_mode`` bits 16..23, DO_SET_MODE param2)."""

    MANUAL = 1
    ALTCTL = 2
    POSCTL = 3
    AUTO = 4
    ACRO = 5
    OFFBOARD = 6
    STABILIZED = 7
    RATTITUDE = 8

    @property
    def text(self) -> str:
        """Name as PX4's ground stations show it."""
        return self.name.capitalize() if self is not Px4MainMode.ALTCTL else "Altitude"


class Px4AutoSubMode(IntEnum):
    """PX4 sub modes of AUTO (``custom_mode`` bits 24..31, DO_SET_MODE param3)."""

    READY = 1
    TAKEOFF = 2
    LOITER = 3
    MISSION = 4
    RTL = 5
    LAND = 6
    FOLLOW_TARGET = 8
    PRECLAND = 9


def px4_custom_mode(main: Px4MainMode, sub: Px4AutoSubMode | None = None) -> int:
    """``HEARTBEAT.custom_mode`` value PX4 reports for a main (and sub) mode."""
    return (int(main) << 16) | ((int(sub) if sub is not None else 0) << 24)


def split_px4_custom_mode(custom_mode: int) -> tuple[int, int]:
    """(main mode, sub mode) numbers from a PX4 ``custom_mode``."""
    return (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF


def px4_mode_text(custom_mode: int) -> str:
    """Readable PX4 mode, e.g. ``"OFFBOARD"`` or ``"AUTO.LAND"``."""
    main, sub = split_px4_custom_mode(custom_mode)
    try:
        name = Px4MainMode(main).name
    except ValueError:
        return f"PX4 mode {main}.{sub}"
    if main == Px4MainMode.AUTO and sub:
        try:
            return f"{name}.{Px4AutoSubMode(sub).name}"
        except ValueError:
            return f"{name}.{sub}"
    return name


class CopterMode(IntEnum):
    """ArduCopter flight modes (``custom_mode``, DO_SET_MODE param2)."""

    STABILIZE = 0
    ACRO = 1
    ALT_HOLD = 2
    AUTO = 3
    GUIDED = 4
    LOITER = 5
    RTL = 6
    CIRCLE = 7
    LAND = 9
    POSHOLD = 16
    BRAKE = 17
    SMART_RTL = 21

    @property
    def text(self) -> str:
        """Name as ArduPilot's ground stations show it."""
        return self.name.replace("_", " ").title()


def copter_mode_text(custom_mode: int) -> str:
    """ArduCopter mode name such as ``GUIDED``."""
    try:
        return CopterMode(custom_mode).name
    except ValueError:
        return f"Copter mode {custom_mode}"


def sim_mode_text(custom_mode: int) -> str:
    """:class:`SimMode` name."""
    try:
        return SimMode(custom_mode).name
    except ValueError:
        return f"sim mode {custom_mode}"


def heartbeat_mode_text(autopilot: int, custom_mode: int) -> str:
    """Mode name of a HEARTBEAT whose profile is not known (a recorded log).

    The ``MAV_AUTOPILOT`` field picks the names: ArduPilot's and PX4's, and the
    simulated vehicles' for a generic autopilot (the only generic one we fly).
    """
    if autopilot == mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA:
        return copter_mode_text(custom_mode)
    if autopilot == mavlink.MAV_AUTOPILOT_PX4:
        return px4_mode_text(custom_mode)
    return sim_mode_text(custom_mode)
