"""A rolling window of what the paper's experiment figure shows.

Inter-vehicle distances against their desired values (the scale times the
shape's distances) and the vehicles' x/y velocities in the navigation frame,
one sample per guidance tick, from the loop's own snapshot so that the plot
shows exactly what the guidance saw.
"""

from __future__ import annotations

import collections
from dataclasses import dataclass

import numpy as np

from gcs.loop import RuntimeSnapshot
from web._frame import TeamView

__all__ = ["History", "Series"]


@dataclass(frozen=True, eq=False)
class Series:
    """Samples of the window, oldest first."""

    t: np.ndarray  # (k,) loop time, s
    distance: np.ndarray  # (k, m) actual horizontal distance per edge, m
    desired: np.ndarray  # (k, m) scale * desired distance per edge, m
    vx: np.ndarray  # (k, n) north velocity per vehicle, m/s
    vy: np.ndarray  # (k, n) east velocity per vehicle, m/s


class History:
    """The last ``window`` seconds of distances and velocities.

    Args:
        view: the team.
        window: span kept, s.
    """

    def __init__(self, view: TeamView, *, window: float = 60.0) -> None:
        self.view = view
        self.window = window
        self._samples: collections.deque[tuple[float, np.ndarray, np.ndarray, np.ndarray]] = \
            collections.deque()
        self._last_t = -np.inf

    def add(self, snap: RuntimeSnapshot) -> bool:
        """Take the snapshot's tick; False if it is not new or the team is not all known."""
        return self.add_sample(snap.fleet.t, snap.fleet.p_ned, snap.fleet.v_ned,
                               snap.demand.scale)

    def add_sample(self, t: float, p_ned: np.ndarray, v_ned: np.ndarray, scale: float) -> bool:
        """Take one tick from plain arrays (the live loop's snapshot or a replayed log)."""
        if t <= self._last_t:
            return False
        p = p_ned[:, :2]
        v = v_ned[:, :2]
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(v))):
            return False
        self._last_t = t
        e = self.view.edges
        distance = np.linalg.norm(p[e[:, 0]] - p[e[:, 1]], axis=1)
        desired = scale * self.view.distances
        self._samples.append((t, distance, desired, v.copy()))
        while self._samples and self._samples[0][0] < t - self.window:
            self._samples.popleft()
        return True

    def __len__(self) -> int:
        return len(self._samples)

    def series(self) -> Series:
        """The window as arrays (empty arrays before the first sample)."""
        m, n = len(self.view.distances), self.view.n
        if not self._samples:
            return Series(np.zeros(0), np.zeros((0, m)), np.zeros((0, m)), np.zeros((0, n)),
                          np.zeros((0, n)))
        t, dist, desired, v = zip(*self._samples, strict=True)
        vel = np.stack(v)
        return Series(np.array(t), np.stack(dist), np.stack(desired), vel[:, :, 0], vel[:, :, 1])
