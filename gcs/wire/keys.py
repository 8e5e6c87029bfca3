"""Every zenoh key expression of the fleet, in one place for the GCS and the sim.

Layout (``<fleet>`` is a name such as ``default``, ``<sysid>`` a MAVLink
system id 1..255 written in decimal)::

    fleet/<fleet>/vehicle/<sysid>/mavlink/to_vehicle    GCS -> vehicle MAVLink 2 frames
    fleet/<fleet>/vehicle/<sysid>/mavlink/from_vehicle  vehicle -> GCS MAVLink 2 frames
    fleet/<fleet>/alive/<sysid>                         liveliness token of a vehicle
    fleet/<fleet>/clock                                 sim clock (sim time, s)
    fleet/<fleet>/clock/ack                             lockstep: the GCS is done up to t
    fleet/<fleet>/sim/<topic...>                        sim-only truth (payload pose, ropes)

Each payload on a ``mavlink`` key holds one or more whole MAVLink frames.
"""

from __future__ import annotations

import re
from enum import Enum

__all__ = [
    "Direction",
    "alive",
    "alive_all",
    "check_fleet",
    "clock",
    "clock_ack",
    "mavlink",
    "mavlink_all",
    "parse_alive",
    "parse_mavlink",
    "sim",
    "sim_all",
]

_FLEET_RE = re.compile(r"[A-Za-z0-9_\-]+(\.[A-Za-z0-9_\-]+)*")


class Direction(Enum):
    """Which way MAVLink frames travel on a key."""

    TO_VEHICLE = "to_vehicle"
    FROM_VEHICLE = "from_vehicle"


def check_fleet(fleet: str) -> str:
    """Return ``fleet`` if it is a usable single key chunk, else raise ValueError.

    Letters, digits, ``_``, ``-`` and inner dots only: no ``/`` or wildcards,
    so one fleet can never subscribe to another's keys by accident.
    """
    if not isinstance(fleet, str) or not _FLEET_RE.fullmatch(fleet):
        raise ValueError(f"fleet name must be letters, digits, '_', '-' or '.', got {fleet!r}")
    return fleet


def _check_sysid(sysid: int) -> int:
    if isinstance(sysid, bool) or not isinstance(sysid, int) or not 1 <= sysid <= 255:
        raise ValueError(f"MAVLink system id must be an integer 1..255, got {sysid!r}")
    return sysid


def mavlink(fleet: str, sysid: int, direction: Direction) -> str:
    """Key of one vehicle's MAVLink frames in one direction."""
    return f"fleet/{check_fleet(fleet)}/vehicle/{_check_sysid(sysid)}/mavlink/{direction.value}"


def mavlink_all(fleet: str, direction: Direction) -> str:
    """Key expression matching every vehicle's frames in one direction."""
    return f"fleet/{check_fleet(fleet)}/vehicle/*/mavlink/{direction.value}"


def alive(fleet: str, sysid: int) -> str:
    """Liveliness token key a vehicle declares while it is up."""
    return f"fleet/{check_fleet(fleet)}/alive/{_check_sysid(sysid)}"


def alive_all(fleet: str) -> str:
    """Key expression matching every vehicle's liveliness token."""
    return f"fleet/{check_fleet(fleet)}/alive/*"


def clock(fleet: str) -> str:
    """Key of the sim clock samples."""
    return f"fleet/{check_fleet(fleet)}/clock"


def clock_ack(fleet: str) -> str:
    """Key on which a lockstep GCS reports the sim time it has finished its tick for."""
    return f"fleet/{check_fleet(fleet)}/clock/ack"


def sim(fleet: str, topic: str) -> str:
    """Key of one sim-only truth topic, e.g. ``sim(f, "payload")`` or ``sim(f, "rope/2")``."""
    parts = topic.split("/")
    if not topic or any(not p or p in {"*", "**"} or any(c in p for c in "$?#") for p in parts):
        raise ValueError(f"sim topic must be '/'-separated non-empty names, got {topic!r}")
    return f"fleet/{check_fleet(fleet)}/sim/{topic}"


def sim_all(fleet: str) -> str:
    """Key expression matching all sim-only truth."""
    return f"fleet/{check_fleet(fleet)}/sim/**"


def parse_alive(key: str) -> int | None:
    """System id from an ``alive`` key, or None if ``key`` is not one."""
    parts = str(key).split("/")
    if len(parts) == 4 and parts[0] == "fleet" and parts[2] == "alive":
        return _parse_sysid(parts[3])
    return None


def parse_mavlink(key: str) -> tuple[int, Direction] | None:
    """(system id, direction) from a ``mavlink`` key, or None if ``key`` is not one."""
    parts = str(key).split("/")
    if len(parts) != 6 or parts[0] != "fleet" or parts[2] != "vehicle" or parts[4] != "mavlink":
        return None
    sysid = _parse_sysid(parts[3])
    try:
        direction = Direction(parts[5])
    except ValueError:
        return None
    return None if sysid is None else (sysid, direction)


def _parse_sysid(text: str) -> int | None:
    if not (text.isascii() and text.isdigit()) or (len(text) > 1 and text[0] == "0"):
        return None
    value = int(text)
    return value if 1 <= value <= 255 else None
