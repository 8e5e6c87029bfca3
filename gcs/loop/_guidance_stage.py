"""The loop's guidance stage: one horizontal acceleration per vehicle for this tick.

In shape, the paper's distance-based guidance (:class:`gcs.guidance.Guidance`,
eq. udi) plus the ropes' leads (:mod:`gcs.loop._rope_lead_stage`); a team held
after a deformation, each vehicle pulled back to its own point
(:meth:`GuidanceStage.damping`); a team that cannot be placed, no horizontal
acceleration. Every acceleration is finite and saturated.
"""

from __future__ import annotations

import numpy as np

from gcs.common import HOLD_KP, HOLD_KV
from gcs.config import Team
from gcs.guidance import Guidance, MotionDemand, finite_max_norm, saturate
from gcs.loop._fleet import FleetState
from gcs.loop._rope_lead_stage import RopeLead

__all__ = ["GuidanceStage"]


class GuidanceStage:
    """The team's accelerations, tick by tick; :attr:`largest` the last tick's largest."""

    def __init__(self, team: Team, guidance: Guidance, rope_lead: RopeLead) -> None:
        self._team = team
        self.guidance = guidance
        self.rope_lead = rope_lead
        self.largest = 0.0
        """Norm of the largest acceleration the last tick commanded, m/s^2 (0: none)."""

    def accelerations(self, fleet: FleetState, demand: MotionDemand, *, hold: bool,
                      hold_points: np.ndarray | None, carrying: bool) -> np.ndarray:
        """(n, 2) NED m/s^2 for ``demand``; ``hold``: each vehicle holds its own point of
        ``hold_points`` (n, 2) instead (None: damps its velocity); ``carrying``: the
        payload hangs (the spin's rope lead applies). What the guidance could not compute
        is zero."""
        if hold:
            accel = self.damping(fleet, hold_points)
        elif fleet.located:
            accel = self.guidance.accelerations(fleet.p_ned[:, :2], fleet.v_ned[:, :2],
                                                fleet.yaw, demand)
            accel = self.rope_lead.apply(fleet, demand, accel, carrying=carrying)
        else:  # cannot place every vehicle: hold still horizontally
            accel = np.zeros((fleet.n, 2))
            self.largest = 0.0
            return accel
        self.largest = finite_max_norm(accel)
        return accel

    def idle(self, n: int) -> np.ndarray:
        """No setpoints this tick: (n, 2) zeros."""
        self.largest = 0.0
        return np.zeros((n, 2))

    def damping(self, fleet: FleetState, hold_points: np.ndarray | None = None) -> np.ndarray:
        """Velocity damping, saturated (NaN: zero), and with ``hold_points`` (n, 2) a pull of
        each vehicle back to its own point: the hold that cannot amplify a deformation
        whatever the positions say, since no vehicle's command depends on another's
        position. The pull is critically damped (``HOLD_KP``, ``HOLD_KV``): damping alone
        lets the shape drift with the wind."""
        v = np.nan_to_num(fleet.v_ned[:, :2], nan=0.0, posinf=0.0, neginf=0.0)
        if hold_points is None:
            accel = -self.guidance.c1 * v
        else:
            offset = np.nan_to_num(fleet.p_ned[:, :2] - hold_points, nan=0.0)
            accel = -HOLD_KV * v - HOLD_KP * offset
        lim = self._team.config.limits
        return saturate(accel, norm_max=lim.accel_norm, axis_max=lim.accel_axis)
