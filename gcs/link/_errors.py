"""Command outcomes and the errors a link raises, each naming the vehicle.

A ``COMMAND_LONG`` ends in a :class:`gcs.wire.CommandResult`: one of MAVLink's
``MAV_RESULT`` values, or ``TIMEOUT`` when no ``COMMAND_ACK`` came back after
all retries. Anything but ``ACCEPTED`` raises
:class:`CommandError`, a ``RuntimeError`` whose text names the vehicle, the
command and the outcome.
"""

from __future__ import annotations

from dataclasses import dataclass

from gcs.wire import CommandResult, command_name

__all__ = ["CommandAck", "CommandError", "LinkError"]


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
