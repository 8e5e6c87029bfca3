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

Anyone on the zenoh fabric can publish here, so a payload is refused
(:class:`ValueError`) before it is parsed if it is longer than
:data:`CONTROL_MAX_BYTES`, and whatever the JSON parser raises on hostile
input (a nesting deep enough to exhaust the recursion limit raised
RecursionError, which killed the sim's loop) becomes a ValueError too.
"""

from __future__ import annotations

import json
import reprlib
from dataclasses import dataclass
from enum import Enum

__all__ = ["CONTROL_MAX_BYTES", "ControlAction", "ControlCommand", "parse_control"]

CONTROL_MAX_BYTES = 1024
"""Longest control payload taken, bytes (a real one is about 35)."""


class ControlAction(Enum):
    """What a control message does to one vehicle."""

    KILL = "kill"
    CUT = "cut"
    RESTORE = "restore"

    @property
    def text(self) -> str:
        """Past tense for logs, e.g. ``"killed"``."""
        return {"kill": "killed", "cut": "cut off", "restore": "restored"}[self.value]


@dataclass(frozen=True)
class ControlCommand:
    """One decoded control message."""

    action: ControlAction
    sysid: int

    def to_bytes(self) -> bytes:
        """The JSON payload of this command."""
        return json.dumps({"action": self.action.value, "sysid": self.sysid}).encode()


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
    if not isinstance(doc, dict) or set(doc) != {"action", "sysid"}:
        raise ValueError("control message must be an object with exactly 'action' and 'sysid'")
    try:
        action = ControlAction(doc["action"])
    except ValueError:
        choices = ", ".join(a.value for a in ControlAction)
        raise ValueError(f"control action must be one of {choices}, got "
                         f"{reprlib.repr(doc['action'])}") from None
    sysid = doc["sysid"]
    if isinstance(sysid, bool) or not isinstance(sysid, int):
        raise ValueError(f"control sysid must be an integer, got {reprlib.repr(sysid)}")
    return ControlCommand(action, sysid)
