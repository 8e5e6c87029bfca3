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
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from enum import Enum

__all__ = ["ControlAction", "ControlCommand", "parse_control"]


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
    """Decode a control payload; ValueError naming the fault otherwise."""
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
        raise ValueError(f"control action must be one of {choices}, got {doc['action']!r}") \
            from None
    sysid = doc["sysid"]
    if isinstance(sysid, bool) or not isinstance(sysid, int):
        raise ValueError(f"control sysid must be an integer, got {sysid!r}")
    return ControlCommand(action, sysid)
