"""Outcomes of a request to the onboard autopilot: accepted, or denied and why.

A vehicle's :mod:`~vehicles.endpoint` answers each COMMAND_LONG from one of
these; the modes and setpoint kinds themselves are wire values
(:class:`gcs.wire.SimMode`, :class:`gcs.wire.SetpointKind`).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

__all__ = ["Denial", "RequestOutcome"]


class Denial(Enum):
    """Why a command was refused; the value is the operator-facing text."""

    DISARMED = "vehicle is disarmed"
    ARMED = "vehicle is armed"
    IN_FLIGHT = "vehicle is in flight"
    NO_POSE = "no position measurement received yet"
    NO_SETPOINT_STREAM = "no setpoint received within the setpoint timeout"
    BAD_ALTITUDE = "takeoff altitude must exceed the ground clearance"


@dataclass(frozen=True)
class RequestOutcome:
    """Outcome of a mode or arming request; the endpoint answers it with a COMMAND_ACK."""

    accepted: bool
    denial: Denial | None = None

    def __post_init__(self) -> None:
        if self.accepted == (self.denial is not None):
            raise ValueError("a request outcome has a denial reason exactly when it is denied")

    @property
    def text(self) -> str:
        """``"accepted"`` or ``"denied: <reason>"``."""
        if self.accepted:
            return "accepted"
        return f"denied: {self.denial.value}"  # type: ignore[union-attr]
