"""Which vehicles are present: appear/vanish events and the configured ones that are missing.

Two independent witnesses report presence: a vehicle's zenoh liveliness token
(simulated vehicles; it vanishes the moment their session closes) and its
MAVLink HEARTBEAT (every vehicle; gone once older than the link's timeout).
A vehicle counts as present while any witness says so. Each change of a
witness's opinion is one :class:`PresenceEvent`, delivered to the callback
and kept in a queue for pollers.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from enum import Enum

__all__ = ["Discovery", "Presence", "PresenceEvent", "PresenceSource"]

_log = logging.getLogger(__name__)


class PresenceSource(Enum):
    """Who witnessed a change."""

    LIVELINESS = "zenoh liveliness token"
    HEARTBEAT = "MAVLink heartbeat"


class Presence(Enum):
    """What changed."""

    APPEARED = "appeared"
    VANISHED = "vanished"


@dataclass(frozen=True)
class PresenceEvent:
    """One witness's change of opinion about one vehicle."""

    sysid: int
    presence: Presence
    source: PresenceSource
    configured: bool
    """True if the vehicle is one of the configured links."""
    at: float
    """Clock time of the report, s."""

    @property
    def text(self) -> str:
        """E.g. ``"vehicle 3 vanished (zenoh liveliness token)"``."""
        extra = "" if self.configured else ", not configured"
        return f"vehicle {self.sysid} {self.presence.value} ({self.source.value}{extra})"


class Discovery:
    """Collects presence reports; thread-safe."""

    def __init__(self, configured: Iterable[int], *, clock: Callable[[], float] = time.monotonic,
                 on_event: Callable[[PresenceEvent], None] | None = None,
                 history: int = 1000) -> None:
        self._configured = frozenset(configured)
        self._clock = clock
        self._on_event = on_event
        self._lock = threading.Lock()
        self._state: dict[tuple[int, PresenceSource], bool] = {}
        self._queue: deque[PresenceEvent] = deque(maxlen=history)

    @property
    def configured(self) -> frozenset[int]:
        """System ids of the configured vehicles."""
        return self._configured

    def report(self, sysid: int, present: bool, source: PresenceSource) -> PresenceEvent | None:
        """A witness's current opinion; returns the event if it changed."""
        key = (sysid, source)
        with self._lock:
            if self._state.get(key, False) == present:
                return None
            self._state[key] = present
            event = PresenceEvent(sysid, Presence.APPEARED if present else Presence.VANISHED,
                                  source, sysid in self._configured, self._clock())
            self._queue.append(event)
        if self._on_event is not None:
            try:
                self._on_event(event)
            except Exception:
                _log.exception("presence callback failed for %s", event.text)
        return event

    def events(self) -> list[PresenceEvent]:
        """Events since the last call, oldest first."""
        with self._lock:
            out = list(self._queue)
            self._queue.clear()
        return out

    def present(self) -> frozenset[int]:
        """Vehicles that at least one witness currently sees."""
        with self._lock:
            return frozenset(sysid for (sysid, _), up in self._state.items() if up)

    def missing(self) -> tuple[int, ...]:
        """Configured vehicles no witness sees, sorted."""
        present = self.present()
        return tuple(sorted(self._configured - present))

    def missing_text(self) -> str:
        """E.g. ``"configured vehicles not seen: 2, 4"``; empty when all are present."""
        missing = self.missing()
        if not missing:
            return ""
        return "configured vehicles not seen: " + ", ".join(str(s) for s in missing)
