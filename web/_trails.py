"""Short trails behind each vehicle: where the team has just been.

A fixed ring of samples per vehicle, taken at a fixed rate whatever the UI's
frame rate, so a trail always spans the same time and costs the same to draw.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Trails"]


class Trails:
    """Recent positions of ``n`` vehicles.

    Args:
        n: number of vehicles.
        span: how far back a trail reaches, s.
        rate: samples per second.
    """

    def __init__(self, n: int, *, span: float = 10.0, rate: float = 5.0) -> None:
        self.capacity = max(2, round(span * rate))
        self.period = 1.0 / rate
        self._p = np.full((self.capacity, n, 3), np.nan)
        self._count = 0
        self._next_t = -np.inf
        self._segments: tuple[np.ndarray, np.ndarray] | None = None

    def add(self, t: float, p_ned: np.ndarray) -> bool:
        """Take a sample at time ``t`` if one is due; True if taken."""
        if t < self._next_t:
            return False
        self._next_t = t + self.period
        self._p = np.roll(self._p, -1, axis=0)
        self._p[-1] = p_ned
        self._count = min(self._count + 1, self.capacity)
        self._segments = None
        return True

    def segments(self) -> tuple[np.ndarray, np.ndarray]:
        """Line segments (k, 2, 3) joining consecutive known samples, and each one's age
        as a fraction of the span in [0, 1) (k,), oldest first, vehicle after vehicle.

        The same arrays are returned until the next sample is taken.
        """
        if self._segments is None:
            self._segments = self._build()
        return self._segments

    def _build(self) -> tuple[np.ndarray, np.ndarray]:
        p = self._p[self.capacity - self._count:]
        if len(p) < 2:
            return np.zeros((0, 2, 3)), np.zeros(0)
        seg = np.stack((p[:-1], p[1:]), axis=2)  # (s-1, n, 2, 3)
        age = np.broadcast_to(((len(p) - 2 - np.arange(len(p) - 1)) / self.capacity)[:, None],
                              seg.shape[:2])
        ok = np.all(np.isfinite(seg), axis=(2, 3))
        seg = np.swapaxes(seg, 0, 1)[np.swapaxes(ok, 0, 1)]
        age = np.swapaxes(age, 0, 1)[np.swapaxes(ok, 0, 1)]
        return seg, age
