"""The operator's event log: phase changes, warnings and errors, shown and recorded.

Every stage of the loop says what the operator should see through one
:class:`EventLog`; a condition that holds tick after tick is said once
(:meth:`EventLog.warn_once`) until it clears (:meth:`EventLog.unlatch`).
"""

from __future__ import annotations

import collections
import threading
from collections.abc import Callable
from dataclasses import dataclass

from gcs.loop._record import FlightRecorder

__all__ = ["LEVELS", "Event", "EventLog"]

LEVELS = ("info", "warning", "error")
"""The levels of an event, least urgent first."""

_SEVERITY = {"info": 6, "warning": 4, "error": 3}
"""MAVLink ``MAV_SEVERITY`` of each level, as recorded."""


@dataclass(frozen=True)
class Event:
    """Something the operator should see: a phase change, a warning, an error."""

    t: float
    level: str  # "info", "warning", "error"
    text: str


class EventLog:
    """The recent events (200), the count of errors, and their record; thread-safe."""

    def __init__(self, clock: Callable[[], float], recorder: FlightRecorder | None) -> None:
        self._clock = clock
        self._recorder = recorder
        self._lock = threading.Lock()
        self._events: collections.deque[Event] = collections.deque(maxlen=200)
        self._latched: set[tuple[str, int]] = set()
        self.errors = 0
        """Error events so far (the log keeps only the recent ones)."""

    def add(self, level: str, text: str) -> None:
        """Say ``text`` at ``level`` now."""
        t = self._clock()
        with self._lock:
            self._events.append(Event(t, level, text))
            if level == "error":
                self.errors += 1
        if self._recorder is not None:
            self._recorder.text(t, text, severity=_SEVERITY[level])

    def note(self, level: str, text: str) -> None:
        """:meth:`add` from outside the loop (link presence, UI, gamepad): the level checked."""
        if level not in LEVELS:
            raise ValueError(f"event level must be info, warning or error, got {level!r}")
        self.add(level, text)

    def recent(self) -> tuple[Event, ...]:
        """The recent events, oldest first."""
        with self._lock:
            return tuple(self._events)

    def warn_once(self, key: tuple[str, int], text: str) -> None:
        """Say ``text`` once for a condition that may hold tick after tick; again only
        after :meth:`unlatch` (the condition cleared). Some are never unlatched: a
        setpoint that cannot be sent, the analysis, the rope lead turned off."""
        if key not in self._latched:
            self._latched.add(key)
            self.add("warning", text)

    def unlatch(self, key: tuple[str, int]) -> None:
        """The condition behind ``key`` cleared: its next occurrence is said again."""
        self._latched.discard(key)
