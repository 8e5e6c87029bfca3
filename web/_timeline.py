"""Replay time: where in the log the page is, and how fast it moves.

Pure bookkeeping (no viser, no clock of its own): the UI thread calls
:meth:`Timeline.advance` with the wall time elapsed, the buttons call
:meth:`play`, :meth:`pause`, :meth:`seek` and set :attr:`speed`. Keeping it apart
from the page makes play/pause/scrub testable without a browser.
"""

from __future__ import annotations

import threading

__all__ = ["SPEEDS", "Timeline"]

SPEEDS: tuple[float, ...] = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
"""Replay speeds offered, times real time."""


class Timeline:
    """A play head on ``[start, end]`` (log time, Unix s); thread-safe.

    Args:
        start: first moment of the log, s.
        end: last moment of the log, s.
    """

    def __init__(self, start: float, end: float) -> None:
        self.start = float(start)
        self.end = max(float(end), self.start)
        self._t = self.start
        self._speed = 1.0
        self._playing = False
        self._lock = threading.Lock()

    @property
    def t(self) -> float:
        """Current log time, s."""
        return self._t

    @property
    def elapsed(self) -> float:
        """Seconds since the start of the log."""
        return self._t - self.start

    @property
    def duration(self) -> float:
        return self.end - self.start

    @property
    def playing(self) -> bool:
        return self._playing

    @property
    def speed(self) -> float:
        return self._speed

    @speed.setter
    def speed(self, value: float) -> None:
        """Clamped to the offered range (0.25x to 16x)."""
        self._speed = min(max(float(value), SPEEDS[0]), SPEEDS[-1])

    def play(self) -> None:
        """Play from here; from the start again when at the end."""
        with self._lock:
            if self._t >= self.end:
                self._t = self.start
            self._playing = True

    def pause(self) -> None:
        self._playing = False

    def seek(self, t: float) -> None:
        """Jump to log time ``t`` (clamped to the log)."""
        with self._lock:
            self._t = min(max(float(t), self.start), self.end)

    def advance(self, wall_dt: float) -> float:
        """Move on by ``wall_dt`` wall seconds if playing; pauses at the end. Returns t."""
        with self._lock:
            if self._playing:
                self._t = min(self._t + self._speed * max(wall_dt, 0.0), self.end)
                if self._t >= self.end:
                    self._playing = False
            return self._t
