"""Everything that reaches the sim host from other threads, in arrival order.

Why: zenoh and UDP deliver on their own threads, but the world and the
autopilots belong to the host's loop. Receivers decode and answer what needs
no simulation state (setpoint echoes, :meth:`vehicles.endpoint.VehicleEndpoint.take`)
and push the rest here; the loop takes it between chunks of physics (or while
it waits for wall time), so inbound setpoints and commands act at
well-defined sim times and no lock guards the simulation. A
:class:`queue.SimpleQueue` is used because its ``put`` is safe even from a
signal handler.
"""

from __future__ import annotations

import queue
from collections.abc import Sequence
from dataclasses import dataclass

from vehicles.endpoint import Inbound

__all__ = ["ClockAck", "ControlMessage", "Inbox", "InboxItem", "Received", "Stop"]


@dataclass(frozen=True, slots=True)
class Received:
    """What vehicle ``index``'s endpoint took from one payload and left for the loop."""

    index: int
    inbound: Sequence[Inbound]


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


InboxItem = Received | ClockAck | ControlMessage | Stop


class Inbox:
    """Thread-safe FIFO of :data:`InboxItem`; any thread puts, the host loop gets."""

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue[InboxItem] = queue.SimpleQueue()

    def put(self, event: InboxItem) -> None:
        """Add an event; never blocks (safe in signal handlers)."""
        self._queue.put(event)

    def get(self, timeout_s: float) -> InboxItem | None:
        """The next event, waiting at most ``timeout_s`` (0: do not wait); None if none came."""
        try:
            if timeout_s <= 0.0:
                return self._queue.get_nowait()
            return self._queue.get(timeout=timeout_s)
        except queue.Empty:
            return None
