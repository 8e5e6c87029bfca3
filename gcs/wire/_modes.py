"""Flight-mode numbers of every autopilot the GCS drives, in one place.

MAVLink leaves the meaning of ``HEARTBEAT.custom_mode`` and of
``MAV_CMD_DO_SET_MODE`` param2/param3 to each autopilot. The simulated
vehicles' numbers are *defined* here (the sim imports them); PX4's and
ArduCopter's are copied from their sources (PX4 ``px4_custom_mode.h``,
ArduCopter ``mode.h``).

Simulated vehicles present themselves as PX4 does, so that QGroundControl,
MAVProxy and pymavlink name their modes: ``HEARTBEAT`` with type
``MAV_TYPE_QUADROTOR``, autopilot ``MAV_AUTOPILOT_PX4``, ``base_mode`` from
:func:`px4_base_mode` and ``custom_mode`` the PX4 mode of :data:`SIM_PX4_MODES`
(the autopilot's own modes stay the :class:`SimMode` values its kernel stores).
A mode change is ``MAV_CMD_DO_SET_MODE`` (or the ``SET_MODE`` message) with
PX4's main and sub mode (:func:`sim_mode_for_px4` says what each asks of the
vehicle). Simulators before this spoke ``MAV_AUTOPILOT_GENERIC`` with
``custom_mode`` = the :class:`SimMode` value itself; :func:`sim_mode_of` reads
both, so recorded flights and such peers still read right.
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import IntEnum
from types import MappingProxyType

from gcs.wire._dialect import mavlink

__all__ = [
    "CUSTOM_MODE_ENABLED",
    "SAFETY_ARMED",
    "SIM_PX4_MODES",
    "CopterMode",
    "Px4AutoSubMode",
    "Px4MainMode",
    "SimMode",
    "copter_mode_text",
    "heartbeat_mode_text",
    "px4_base_mode",
    "px4_custom_mode",
    "px4_mode_text",
    "sim_mode_for_px4",
    "sim_mode_of",
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


def px4_custom_mode(main: int, sub: int | None = None) -> int:
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


_AUTO_FLAGS = (mavlink.MAV_MODE_FLAG_AUTO_ENABLED | mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
               | mavlink.MAV_MODE_FLAG_GUIDED_ENABLED)
_MANUAL = mavlink.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
_STABILIZE = mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
_PX4_FLAGS: dict[int, int] = {
    Px4MainMode.MANUAL: _MANUAL | _STABILIZE,
    Px4MainMode.ALTCTL: _MANUAL | _STABILIZE,
    Px4MainMode.POSCTL: _MANUAL | _STABILIZE | mavlink.MAV_MODE_FLAG_GUIDED_ENABLED,
    Px4MainMode.AUTO: _AUTO_FLAGS,
    Px4MainMode.ACRO: _MANUAL,
    Px4MainMode.OFFBOARD: _AUTO_FLAGS,
    Px4MainMode.STABILIZED: _MANUAL | _STABILIZE,
    Px4MainMode.RATTITUDE: _MANUAL,
}
"""``base_mode`` flags of each PX4 main mode on a multicopter (PX4's
``get_mavlink_navigation_mode``; pymavlink's ``px4_map`` sends the same as DO_SET_MODE
param1)."""


def px4_base_mode(custom_mode: int, *, armed: bool) -> int:
    """``HEARTBEAT.base_mode`` PX4 sends with ``custom_mode``."""
    main, _ = split_px4_custom_mode(custom_mode)
    return (CUSTOM_MODE_ENABLED | (SAFETY_ARMED if armed else 0)
            | _PX4_FLAGS.get(main, 0))


SIM_PX4_MODES: Mapping[SimMode, int] = MappingProxyType({
    SimMode.DISARMED: px4_custom_mode(Px4MainMode.AUTO, Px4AutoSubMode.LOITER),
    SimMode.TAKEOFF: px4_custom_mode(Px4MainMode.AUTO, Px4AutoSubMode.TAKEOFF),
    SimMode.HOLD: px4_custom_mode(Px4MainMode.AUTO, Px4AutoSubMode.LOITER),
    SimMode.OFFBOARD: px4_custom_mode(Px4MainMode.OFFBOARD),
    SimMode.LAND: px4_custom_mode(Px4MainMode.AUTO, Px4AutoSubMode.LAND),
})
"""PX4 ``custom_mode`` a simulated vehicle reports in each of its modes: TAKEOFF is
AUTO.TAKEOFF, HOLD AUTO.LOITER (PX4's Hold; POSCTL or ALTCTL instead when that is what the
vehicle was asked for, see :func:`sim_mode_for_px4`), OFFBOARD OFFBOARD, LAND AUTO.LAND.
DISARMED is AUTO.LOITER without ``SAFETY_ARMED``: as on PX4, disarmed is no mode of its own."""

_PX4_HOLDS = frozenset({Px4MainMode.POSCTL, Px4MainMode.ALTCTL})
_PX4_AUTO: Mapping[int, SimMode] = MappingProxyType({Px4AutoSubMode.LOITER: SimMode.HOLD,
                              Px4AutoSubMode.TAKEOFF: SimMode.TAKEOFF,
                              Px4AutoSubMode.LAND: SimMode.LAND})


def sim_mode_for_px4(main: int, sub: int = 0) -> SimMode | None:
    """What a PX4 mode (main, sub) asks of a simulated vehicle, or None for a mode it lacks.

    OFFBOARD flies the GCS's setpoints; AUTO.LOITER, POSCTL and ALTCTL hold the position
    (with no sticks, PX4's position and altitude modes hold too); AUTO.TAKEOFF climbs to
    ``MIS_TAKEOFF_ALT``; AUTO.LAND lands. Manual modes (no stick input), missions, RTL and
    the rest are not modes of this vehicle.
    """
    if main == Px4MainMode.OFFBOARD:
        return SimMode.OFFBOARD
    if main in _PX4_HOLDS:
        return SimMode.HOLD
    if main == Px4MainMode.AUTO:
        return _PX4_AUTO.get(sub)
    return None


def sim_mode_of(custom_mode: int, *, armed: bool = True) -> SimMode | None:
    """The :class:`SimMode` a simulated vehicle's HEARTBEAT shows, None if it shows none.

    Reads PX4 custom modes (main mode in bits 16..23, so at least 0x10000) and the bare
    :class:`SimMode` values earlier simulators sent; a vehicle that is not armed is DISARMED.
    """
    if not armed:
        return SimMode.DISARMED
    if 0 < custom_mode < 0x10000:
        try:
            return SimMode(custom_mode)
        except ValueError:
            return None
    return sim_mode_for_px4(*split_px4_custom_mode(custom_mode))


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
    """:class:`SimMode` name of a bare :class:`SimMode` value (earlier simulators' custom
    mode)."""
    try:
        return SimMode(custom_mode).name
    except ValueError:
        return f"sim mode {custom_mode}"


def heartbeat_mode_text(autopilot: int, custom_mode: int) -> str:
    """Mode name of a HEARTBEAT whose profile is not known (a recorded log).

    The ``MAV_AUTOPILOT`` field picks the names: ArduPilot's and PX4's (this simulator's
    vehicles too), and :class:`SimMode` names for a generic autopilot (the simulators
    before PX4's identity, in older recordings).
    """
    if autopilot == mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA:
        return copter_mode_text(custom_mode)
    if autopilot == mavlink.MAV_AUTOPILOT_PX4:
        return px4_mode_text(custom_mode)
    return sim_mode_text(custom_mode)
