"""What a link needs from a byte carrier (zenoh, UDP, TCP, serial).

A transport moves MAVLink frames as bytes and nothing else: framing,
checking and decoding stay in the link, so simulated and real vehicles are
handled by exactly the same code above this interface.
"""

from __future__ import annotations

from collections.abc import Callable
from enum import Enum
from typing import Protocol

__all__ = ["FrameDirection", "Transport"]


class FrameDirection(Enum):
    """Direction of a frame as seen by the link's owner."""

    IN = "received"
    OUT = "sent"


class Transport(Protocol):
    """A byte carrier for one vehicle's MAVLink frames."""

    @property
    def datagram(self) -> bool:
        """True if every received chunk holds whole frames (UDP, zenoh); False for streams."""
        ...

    @property
    def description(self) -> str:
        """Readable endpoint, e.g. ``zenoh fleet/default/vehicle/2`` or ``udpin:0.0.0.0:14550``."""
        ...

    def start(self, on_bytes: Callable[[bytes], None]) -> None:
        """Deliver received bytes to ``on_bytes`` on a transport-owned thread; non-blocking."""
        ...

    def send(self, frame: bytes) -> None:
        """Send one or more whole frames; non-blocking, silently lossy like the radio it models."""
        ...

    def close(self) -> None:
        """Stop receiving and release the endpoint; idempotent."""
        ...
