"""The sim's control topic: test hooks that break a vehicle on purpose.

Why: failure handling (a vehicle that dies, a radio link that drops) must be
testable against the real sim process. Messages are JSON objects on
``fleet/<fleet>/sim/control`` (:func:`gcs.wire.keys.sim` with topic
``"control"``)::

    {"action": "kill", "sysid": 3}      vehicle 3 dies: its MAVLink endpoint and
                                         liveliness token go away, its motors stop
    {"action": "cut", "sysid": 3}       its link goes silent both ways; the vehicle
                                         keeps flying its failsafe (setpoint timeout
                                         -> HOLD -> LAND); the token stays (the
                                         process is up, only the radio is gone)
    {"action": "restore", "sysid": 3}   ends a cut (a kill is final)
    {"action": "cut", "sysid": 3, "seconds": 1.5}
                                         a cut the sim ends itself after 1.5 s of
                                         sim time (the same instant on every run)
    {"action": "gust", "sysid": 0, "ned": [2.0, 0.0, 0.0], "seconds": 3}
                                         2 m/s more wind towards north on the whole
                                         world (sysid 0: every vehicle and the
                                         payload) for 3 s of sim time

Anyone on the zenoh fabric can publish here, so a payload is refused
(:class:`ValueError`) before it is parsed if it is longer than
:data:`CONTROL_MAX_BYTES`, and whatever the JSON parser raises on hostile
input (a nesting deep enough to exhaust the recursion limit raised
RecursionError, which killed the sim's loop) becomes a ValueError too.
"""

from __future__ import annotations

import json
import math
import reprlib
from dataclasses import dataclass
from enum import Enum

__all__ = ["CONTROL_MAX_BYTES", "FAULT_MAX_S", "GUST_MAX_M_S", "ControlAction",
           "ControlCommand", "parse_control"]

CONTROL_MAX_BYTES = 1024
"""Longest control payload taken, bytes (a real one is about 35)."""

FAULT_MAX_S = 3600.0
"""Longest timed cut or gust, s of sim time (a test flight, as a scenario's steps)."""

GUST_MAX_M_S = 30.0
"""Largest gust per axis, m/s (a gale; more is a typo, not a test)."""


class ControlAction(Enum):
    """What a control message does to one vehicle."""

    KILL = "kill"
    CUT = "cut"
    RESTORE = "restore"
    GUST = "gust"

    @property
    def text(self) -> str:
        """Past tense for logs, e.g. ``"killed"``."""
        return {"kill": "killed", "cut": "cut off", "restore": "restored",
                "gust": "blown by a gust"}[self.value]


#: The keys each action takes beside ``action`` and ``sysid``: (required, optional).
_MORE_KEYS: dict[ControlAction, tuple[frozenset[str], frozenset[str]]] = {
    ControlAction.KILL: (frozenset(), frozenset()),
    ControlAction.CUT: (frozenset(), frozenset({"seconds"})),
    ControlAction.RESTORE: (frozenset(), frozenset()),
    ControlAction.GUST: (frozenset({"ned", "seconds"}), frozenset()),
}


@dataclass(frozen=True)
class ControlCommand:
    """One decoded control message; ``sysid`` 0 (MAVLink's broadcast) for a gust."""

    action: ControlAction
    sysid: int
    seconds: float | None = None
    """How long a cut or a gust lasts, s of sim time (None: a cut until restored)."""
    wind_ned: tuple[float, float, float] | None = None
    """A gust's wind, added to the world's, NED, m/s."""

    def to_bytes(self) -> bytes:
        """The JSON payload of this command."""
        doc: dict[str, object] = {"action": self.action.value, "sysid": self.sysid}
        if self.wind_ned is not None:
            doc["ned"] = list(self.wind_ned)
        if self.seconds is not None:
            doc["seconds"] = self.seconds
        return json.dumps(doc).encode()


def parse_control(data: bytes) -> ControlCommand:
    """Decode a control payload; ValueError naming the fault, and nothing else, otherwise."""
    if len(data) > CONTROL_MAX_BYTES:
        raise ValueError(f"control message of {len(data)} bytes, more than "
                         f"{CONTROL_MAX_BYTES}")
    try:
        return _parse(data)
    except ValueError:
        raise
    except Exception as exc:  # RecursionError on deep nesting, and whatever else may come
        raise ValueError(f"control message is malformed: {type(exc).__name__}") from None


def _parse(data: bytes) -> ControlCommand:
    try:
        doc = json.loads(data)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"control message is not JSON: {exc}") from None
    if not isinstance(doc, dict) or not {"action", "sysid"} <= set(doc):
        raise ValueError("control message must be an object with 'action' and 'sysid'")
    try:
        action = ControlAction(doc["action"])
    except (ValueError, TypeError):
        choices = ", ".join(a.value for a in ControlAction)
        raise ValueError(f"control action must be one of {choices}, got "
                         f"{reprlib.repr(doc['action'])}") from None
    required, optional = _MORE_KEYS[action]
    more = set(doc) - {"action", "sysid"}
    if not required <= more <= required | optional:
        takes = ", ".join(sorted(required | optional)) or "nothing more"
        raise ValueError(f"control action {action.value} takes {takes} beside action and "
                         f"sysid, got {reprlib.repr(sorted(more))}")
    sysid = doc["sysid"]
    if isinstance(sysid, bool) or not isinstance(sysid, int):
        raise ValueError(f"control sysid must be an integer, got {reprlib.repr(sysid)}")
    if action is ControlAction.GUST and sysid != 0:
        raise ValueError(f"a gust blows on the whole world: sysid 0, got {sysid}")
    seconds = _number(doc["seconds"], "seconds", 0.0, FAULT_MAX_S) if "seconds" in doc else None
    if seconds is not None and seconds <= 0.0:
        raise ValueError(f"control seconds must be above 0, got {seconds:g}")
    wind = None
    if "ned" in doc:
        ned = doc["ned"]
        if not isinstance(ned, list) or len(ned) != 3:
            raise ValueError(f"control ned must be 3 numbers, got {reprlib.repr(ned)}")
        n, e, d = (_number(x, "ned", -GUST_MAX_M_S, GUST_MAX_M_S) for x in ned)
        wind = (n, e, d)
    return ControlCommand(action, sysid, seconds, wind)


def _number(value: object, name: str, lo: float, hi: float) -> float:
    """``value`` as a finite float in [lo, hi]; ValueError naming ``name`` otherwise."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"control {name} must be numbers, got {reprlib.repr(value)}")
    x = float(value)
    if not (math.isfinite(x) and lo <= x <= hi):
        raise ValueError(f"control {name} must lie in [{lo:g}, {hi:g}], got {x:g}")
    return x
