"""What a ``COMMAND_ACK`` says: MAVLink's ``MAV_RESULT`` values, named once.

The simulated vehicles answer with them and the GCS's links read them; two
values are the GCS's own (a result it does not know, no answer at all).
"""

from __future__ import annotations

from enum import IntEnum

__all__ = ["CommandResult"]


class CommandResult(IntEnum):
    """Outcome of a command: ``MAV_RESULT`` values plus TIMEOUT and UNKNOWN."""

    ACCEPTED = 0
    TEMPORARILY_REJECTED = 1
    DENIED = 2
    UNSUPPORTED = 3
    FAILED = 4
    IN_PROGRESS = 5
    CANCELLED = 6
    COMMAND_LONG_ONLY = 7
    COMMAND_INT_ONLY = 8
    UNSUPPORTED_MAV_FRAME = 9
    UNKNOWN = 254
    """A ``MAV_RESULT`` value this GCS does not know."""
    TIMEOUT = 255
    """No COMMAND_ACK arrived (not a MAVLink value)."""

    @classmethod
    def from_wire(cls, value: int) -> CommandResult:
        """Result from a ``COMMAND_ACK.result`` field."""
        try:
            result = cls(value)
        except ValueError:
            return cls.UNKNOWN
        return cls.UNKNOWN if result in (cls.TIMEOUT, cls.UNKNOWN) else result

    @property
    def text(self) -> str:
        """What the outcome means, for operators."""
        return _RESULT_TEXT[self]


_RESULT_TEXT = {
    CommandResult.ACCEPTED: "accepted",
    CommandResult.TEMPORARILY_REJECTED: "temporarily rejected, try again later",
    CommandResult.DENIED: "denied by the vehicle",
    CommandResult.UNSUPPORTED: "not supported by the vehicle",
    CommandResult.FAILED: "failed on the vehicle",
    CommandResult.IN_PROGRESS: "in progress",
    CommandResult.CANCELLED: "cancelled",
    CommandResult.COMMAND_LONG_ONLY: "only accepted as COMMAND_LONG",
    CommandResult.COMMAND_INT_ONLY: "only accepted as COMMAND_INT",
    CommandResult.UNSUPPORTED_MAV_FRAME: "frame not supported",
    CommandResult.UNKNOWN: "answered with an unknown result",
    CommandResult.TIMEOUT: "got no COMMAND_ACK",
}
