"""Clocks: where every loop takes its time from.

Interactive runs use the wall clock; headless runs follow the simulator's clock
(published on zenoh), so a flight played faster than real time gives the same
result, as ROS ``use_sim_time`` or PX4 lockstep do.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Protocol

__all__ = ["Clock", "ClockStoppedError", "ExternalClock", "WallClock"]


class ClockStoppedError(RuntimeError):
    """The clock's source went away while a loop was waiting on it."""


class Clock(Protocol):
    """Seconds on some time base; ``sleep_until`` blocks until that time (or raises)."""

    def now(self) -> float: ...

    def sleep_until(self, t: float) -> None: ...


class WallClock:
    """Monotonic wall-clock time, seconds since creation."""

    def __init__(self) -> None:
        self._t0 = time.monotonic()

    def now(self) -> float:
        return time.monotonic() - self._t0

    def sleep_until(self, t: float) -> None:
        delay = t - self.now()
        if delay > 0:
            time.sleep(delay)


class ExternalClock:
    """Time pushed by another process (the simulator's clock).

    ``advance(t)`` is called when a clock sample arrives; waiting loops wake up.
    Until the first sample the clock has not started (``now()`` is 0.0): a
    ``sleep_until`` waits for that sample whatever ``t``, so a loop that anchors
    its schedule after it starts on the source's first time, not on a 0.0 it
    read first on one run and not on another. If no sample arrives for
    ``timeout`` wall seconds, ``sleep_until`` raises :class:`ClockStoppedError`
    instead of hanging forever, and the clock stays stopped: the timeout counts from
    the last sample, not from each call, so a second waiter (the scenario behind the
    loop) hears the verdict at once instead of waiting out a timeout of its own.
    """

    def __init__(self, *, timeout: float = 5.0) -> None:
        self._t = 0.0
        self._cond = threading.Condition()
        self._timeout = timeout
        self._closed: str | None = None  # why the clock was closed
        self._started = False  # a sample came
        self._last = 0.0  # monotonic wall time of the last sample that moved the clock

    def advance(self, t: float) -> None:
        """Move to sim time ``t`` if it is later (never back); ValueError if not finite."""
        if not math.isfinite(t):
            raise ValueError(f"clock time must be finite, got {t}")
        with self._cond:
            if t > self._t or not self._started:
                self._t = max(self._t, t)
                self._started = True
                self._last = time.monotonic()
                self._cond.notify_all()

    def close(self, reason: str = "the simulator clock was closed") -> None:
        """Stop the clock: every ``sleep_until`` raises :class:`ClockStoppedError` with
        ``reason`` (the first one given)."""
        with self._cond:
            self._closed = self._closed or reason
            self._cond.notify_all()

    def now(self) -> float:
        with self._cond:
            return self._t

    def sleep_until(self, t: float) -> None:
        with self._cond:
            called = time.monotonic()  # before the first sample, the timeout counts from here
            while self._t < t or not self._started:
                if self._closed:
                    raise ClockStoppedError(self._closed)
                left = (self._last if self._started else called) + self._timeout - time.monotonic()
                if left <= 0:
                    self._closed = (f"no simulator clock sample for {self._timeout:g} s "
                                    f"(stuck at t = {self._t:.3f} s)")
                    self._cond.notify_all()
                    raise ClockStoppedError(self._closed)
                self._cond.wait(left)
