"""Command outcomes and the errors a link raises, each naming the vehicle.

A ``COMMAND_LONG`` ends in a :class:`CommandResult`: one of MAVLink's
``MAV_RESULT`` values, or :attr:`CommandResult.TIMEOUT` when no
``COMMAND_ACK`` came back after all retries. Anything but ``ACCEPTED`` raises
:class:`CommandError`, a ``RuntimeError`` whose text names the vehicle, the
command and the outcome.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

from gcs.wire import command_name

__all__ = ["CommandAck", "CommandError", "CommandResult", "LinkError"]


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


@dataclass(frozen=True)
class CommandAck:
    """A final, accepted answer to a command."""

    command: int
    result: CommandResult
    attempts: int
    """How many times the command was sent."""
    rtt_s: float
    """Time from the last send to the acknowledgement, s."""


class LinkError(RuntimeError):
    """Something the link to one vehicle cannot do; the text names the vehicle."""

    def __init__(self, sysid: int, what: str) -> None:
        self.sysid = sysid
        self.what = what
        """The text without the vehicle's name (for messages that name it already)."""
        super().__init__(f"vehicle {sysid}: {what}")


class CommandError(LinkError):
    """A command that was not accepted (refused, failed or unanswered)."""

    def __init__(self, sysid: int, command: int, result: CommandResult, *, attempts: int,
                 timeout_s: float) -> None:
        self.command = command
        self.result = result
        self.attempts = attempts
        tries = f"{attempts} attempt{'s' if attempts != 1 else ''}"
        if result is CommandResult.TIMEOUT:
            tries += f" of {timeout_s:g} s"
        super().__init__(sysid, f"{command_name(command)} {result.text} ({result.name}) "
                                f"after {tries}")
