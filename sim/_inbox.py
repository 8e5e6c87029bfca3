"""Everything that reaches the sim host from other threads, in arrival order.

Why: zenoh and UDP deliver on their own threads, but the world and the
autopilots belong to the host's loop. Receivers decode and answer what needs
no simulation state (setpoint echoes, :meth:`vehicles.endpoint.VehicleEndpoint.take`)
and push the rest here; the loop takes it between chunks of physics (or while
it waits for wall time), so inbound setpoints and commands act at
well-defined sim times and no lock guards the simulation. A
:class:`queue.SimpleQueue` is used because its ``put`` is safe even from a
signal handler.

What is refused on the way (a payload too long, a malformed control message
or ack) is counted in :class:`Refusals`, which logs the first of each kind
at once and then at most one line per kind every
:data:`REFUSAL_REPORT_PERIOD_S`: a flood of junk must not become a flood
on stderr.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from vehicles.endpoint import Inbound

__all__ = ["REFUSAL_REPORT_PERIOD_S", "ClockAck", "ControlMessage", "Inbox", "InboxItem",
           "Received", "Refusals", "Stop"]

_log = logging.getLogger(__name__)

REFUSAL_REPORT_PERIOD_S = 5.0
"""At most one log line per kind of refused input in this much wall time, s."""


@dataclass(frozen=True, slots=True)
class Received:
    """What vehicle ``index``'s endpoint took from one payload and left for the loop."""

    index: int
    inbound: Sequence[Inbound]


@dataclass(frozen=True, slots=True)
class ClockAck:
    """A lockstep GCS (partner id ``partner``) has finished its tick for sim time ``t`` (s)."""

    t: float
    partner: int


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


class Refusals:
    """Counts refused inputs by kind (e.g. ``"control message"``); any thread."""

    def __init__(self, *, wall_clock: Callable[[], float] = time.monotonic) -> None:
        self._wall = wall_clock
        self._lock = threading.Lock()
        self._counts: Counter[str] = Counter()
        self._unreported: Counter[str] = Counter()
        self._reported_at: dict[str, float] = {}

    def refuse(self, kind: str, why: str, count: int = 1) -> None:
        """Count ``count`` refused inputs of ``kind``; log it unless one was logged lately."""
        now = self._wall()
        with self._lock:
            self._counts[kind] += count
            last = self._reported_at.get(kind)
            if last is not None and now - last < REFUSAL_REPORT_PERIOD_S:
                self._unreported[kind] += count
                return
            self._reported_at[kind] = now
            more = self._unreported.pop(kind, 0)
        if more:
            _log.warning("ignored %s: %s (and %d more since the last report)", kind, why, more)
        else:
            _log.warning("ignored %s: %s", kind, why)

    def counts(self) -> dict[str, int]:
        """Refusals so far per kind."""
        with self._lock:
            return dict(self._counts)

    def summary(self) -> str:
        """One line, e.g. ``"control message 2, clock ack 1"`` ('' if nothing was refused)."""
        return ", ".join(f"{kind} {n}" for kind, n in sorted(self.counts().items()))
