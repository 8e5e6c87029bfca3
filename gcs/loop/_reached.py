"""An altitude reached: each vehicle counted once it has been within tolerance of it.

The take-off, the lift and the set-down end when the team is at their altitude. Asking
for every altitude within the tolerance at one moment need never end on GPS altitudes:
four PX4 SIH vehicles, each wandering +-0.15 m about its take-off altitude, need never be
all within 0.1 m at once, and the take-off would time out. Each vehicle is counted from the
first moment it is there; a new target starts the count again.
"""

from __future__ import annotations

import numpy as np


class AltitudeReached:
    """Which vehicles have reached the current target altitude."""

    def __init__(self) -> None:
        self._target = float("nan")
        self._reached: np.ndarray | None = None

    def reset(self) -> None:
        """Count from here on (a new phase)."""
        self._target, self._reached = float("nan"), None

    def update(self, altitude: np.ndarray, target: float, tolerance: float) -> bool:
        """This moment's altitudes (n,), m up: True once every vehicle has been within
        ``tolerance`` of ``target`` since the target was set (NaN: not there)."""
        there = np.abs(np.asarray(altitude, dtype=float) - target) < tolerance
        if self._reached is None or target != self._target \
                or self._reached.shape != there.shape:
            self._target, self._reached = target, np.zeros(there.shape, dtype=bool)
        self._reached |= there
        return bool(self._reached.all())

    def missing(self) -> np.ndarray:
        """(n,) True where a vehicle has not been there yet."""
        return np.ones(0, dtype=bool) if self._reached is None else ~self._reached
