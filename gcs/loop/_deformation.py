"""A team deformed beyond the safe bound: hold, re-form, or land.

The analysis bounds how far a vehicle may be from the team's centroid before
the ropes pull harder than the horizontal force it has left. Beyond it, the
shape-keeping terms of the guidance are what one would reach for, but they
act on the measured positions, and positions in disagreeing frames (autopilots
with their own origins) look exactly like a deformation: "correcting" one drags
the real team apart (21 m in a flight of four ArduCopters). So the team first
holds, each vehicle on its own point (nothing in a vehicle's command depends on
another's position), and then:

* lands, if the deformation keeps growing by ``safety.deformed_land_growth``
  while held or re-forming;
* re-forms (shape keeping with the motion frozen) after :data:`PROBE_S` of
  hold, only if the positions can be trusted: the team was seen in shape
  earlier and no vehicle's position has jumped since (a jump is a position
  that moved more than :data:`JUMP_M` away from where its previous sample and
  velocity put it: a frame reset, an origin set in flight). A real deformation
  (a gust, a slow link in an abrupt reversal) grows continuously from a good
  shape, so it is re-formed; a start out of shape or a jump is held.
"""

from __future__ import annotations

import enum

import numpy as np

__all__ = ["JUMP_M", "PROBE_S", "Deformation", "DeformationPolicy"]

PROBE_S = 1.0
"""Hold this long before re-forming a deformation the positions can be trusted for, s."""

JUMP_M = 0.5
"""A vehicle's position this far from its previous sample moved by its velocity jumped, m."""


class Deformation(enum.Enum):
    """What the team does about its shape this tick."""

    NONE = "within the safe bound"
    HOLD = "hold each vehicle on its own point"
    REFORM = "shape keeping, motion frozen"
    LAND = "land the team"


class DeformationPolicy:
    """Decides, tick by tick, what a deformed team does (see the module doc).

    Args:
        growth: the growth of the deformation that lands the team, m.
    """

    def __init__(self, *, growth: float) -> None:
        self.growth = growth
        self.trusted = False
        """The team was seen in shape and no position has jumped since."""
        self.hold_points: np.ndarray | None = None
        """(n, 2) where each vehicle holds, while holding."""
        self.held_at: float | None = None  # deformation when the hold began, m
        self._since = 0.0
        self._prev: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def observe(self, p_xy: np.ndarray, v_xy: np.ndarray, sample_t: np.ndarray,
                *, in_shape: bool) -> bool:
        """One tick's positions, velocities and their sample times; True if one jumped.

        ``in_shape``: every vehicle fresh and within the safe bound this tick.
        """
        jumped = False
        prev = self._prev
        if prev is not None:
            p0, v0, t0 = prev
            dt = np.nan_to_num(sample_t - t0, nan=0.0, posinf=0.0, neginf=0.0)
            miss = np.hypot(*(p_xy - (p0 + v0 * dt[:, None])).T)
            jumped = bool(np.any(np.nan_to_num(miss, nan=0.0) > JUMP_M))
        self._prev = (p_xy.copy(), v_xy.copy(), sample_t.copy())
        if jumped:
            self.trusted = False
        elif in_shape:
            self.trusted = True
        return jumped

    def update(self, now: float, *, deformed: bool, deformation: float,
               p_xy: np.ndarray) -> Deformation:
        """This tick's decision, given the safety rule's verdict (``deformed``, with the
        largest distance from the centroid ``deformation``)."""
        if not deformed:
            self.held_at = self.hold_points = None
            return Deformation.NONE
        if self.held_at is None:
            self.held_at, self._since = deformation, now
            self.hold_points = p_xy.copy()
            return Deformation.HOLD
        if deformation > self.held_at + self.growth:
            return Deformation.LAND
        if self.trusted and now - self._since >= PROBE_S:
            return Deformation.REFORM
        return Deformation.HOLD
