"""Pacing of sim time against wall time: N times real time, or as fast as possible.

Why: an interactive run must feel real (speed 1), a demo may run faster, a
headless run as fast as the CPU allows. After a stall (a slow machine, a
lockstep wait) the pacer does not sprint to catch up: it re-anchors, so sim
time never runs faster than asked.
"""

from __future__ import annotations

import time
from collections.abc import Callable

__all__ = ["MAX_LAG_S", "Pacer"]

MAX_LAG_S = 0.1
"""Wall-time lag beyond which the pacer re-anchors instead of catching up, s."""


class Pacer:
    """Wall time by which each sim time is due; ``speed`` None means no pacing."""

    def __init__(self, speed: float | None, *,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if speed is not None and not speed > 0.0:
            raise ValueError(f"speed must be positive, got {speed}")
        self._speed = speed
        self._clock = clock
        self._wall0: float | None = None
        self._sim0 = 0.0

    @property
    def speed(self) -> float | None:
        """Sim seconds per wall second (None: as fast as possible)."""
        return self._speed

    def deadline(self, t_sim: float) -> float | None:
        """Monotonic wall time at which sim time ``t_sim`` is due (None: at once)."""
        if self._speed is None:
            return None
        now = self._clock()
        if self._wall0 is None:
            self._wall0, self._sim0 = now, t_sim
        due = self._wall0 + (t_sim - self._sim0) / self._speed
        if now - due > MAX_LAG_S:
            self._wall0, self._sim0 = now, t_sim
            due = now
        return due
