"""Everything that reaches the sim host from other threads, in arrival order.

Why: zenoh and UDP deliver on their own threads, but the world, the
autopilots and the endpoints belong to the host's loop. Receivers only push
events here; the loop takes them between chunks of physics (or while it
waits for wall time), so inbound frames act at well-defined sim times and no
lock guards the simulation. A :class:`queue.SimpleQueue` is used because its
``put`` is safe even from a signal handler.
"""

from __future__ import annotations

import queue
from dataclasses import dataclass

__all__ = ["ClockAck", "ControlMessage", "Event", "Frame", "Inbox", "Stop"]


@dataclass(frozen=True, slots=True)
class Frame:
    """Bytes received for vehicle ``index`` (one zenoh payload or UDP datagram)."""

    index: int
    data: bytes
    peer: tuple[str, int] | None
    """UDP sender address to answer to; None for zenoh."""


@dataclass(frozen=True, slots=True)
class ClockAck:
    """A lockstep GCS has finished its tick for sim time ``t`` (s)."""

    t: float


@dataclass(frozen=True, slots=True)
class ControlMessage:
    """A raw payload from the control topic (parsed by the loop, which logs bad ones)."""

    data: bytes


@dataclass(frozen=True, slots=True)
class Stop:
    """Leave the loop (SIGINT, SIGTERM)."""


Event = Frame | ClockAck | ControlMessage | Stop


class Inbox:
    """Thread-safe FIFO of :data:`Event`; any thread puts, the host loop gets."""

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue[Event] = queue.SimpleQueue()

    def put(self, event: Event) -> None:
        """Add an event; never blocks (safe in signal handlers)."""
        self._queue.put(event)

    def get(self, timeout_s: float) -> Event | None:
        """The next event, waiting at most ``timeout_s`` (0: do not wait); None if none came."""
        try:
            if timeout_s <= 0.0:
                return self._queue.get_nowait()
            return self._queue.get(timeout=timeout_s)
        except queue.Empty:
            return None
