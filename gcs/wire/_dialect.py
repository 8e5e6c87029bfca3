"""The one pymavlink dialect the project speaks, and name look-ups into it.

ArduPilot's ``ardupilotmega`` dialect is a superset of ``common``: with it the
GCS can decode everything PX4, ArduPilot and the simulated vehicles send.
MAVLink 2 only: the v20 module is imported directly so the process-wide
``MAVLINK20`` environment switch of ``pymavlink.mavutil`` plays no part.
"""

from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["MavMessage", "command_name", "mavlink", "message_id", "message_name"]

MavMessage = mavlink.MAVLink_message
"""Base class of every decoded or encodable message."""


def command_name(command: int) -> str:
    """``MAV_CMD_...`` name of a command id, or ``MAV_CMD(<id>)`` when unknown."""
    entry = mavlink.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None else f"MAV_CMD({command})"


def message_id(name: str) -> int:
    """Numeric id of a message given by name (``"LOCAL_POSITION_NED"``); ValueError if unknown."""
    value = getattr(mavlink, f"MAVLINK_MSG_ID_{name.upper()}", None)
    if not isinstance(value, int):
        raise ValueError(f"unknown MAVLink message {name!r}")
    return value


def message_name(msg_id: int) -> str:
    """Name of a message id (``32`` -> ``"LOCAL_POSITION_NED"``), or ``MSG(<id>)`` when unknown."""
    cls = mavlink.mavlink_map.get(msg_id)
    return cls.msgname if cls is not None else f"MSG({msg_id})"
