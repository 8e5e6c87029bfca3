"""The ropes' lead: the guidance's accelerations ahead of the pulls the ropes are about to
change (:mod:`gcs.guidance._rope_lead`).

Two pulls change faster than the 4 Hz guidance corrects: a spinning team's
ropes turn with it, and the ropes take or give up the payload as the team
climbs through the pickup band (the rate load sharing measures). Each vehicle's
acceleration leads both by ``guidance.rope_lag``.
"""

from __future__ import annotations

import numpy as np

from gcs.analysis import NoHangingPointError, desired_load
from gcs.config import Team
from gcs.formation import fit_rotation
from gcs.guidance import (
    Guidance,
    MotionDemand,
    rope_growth_lead,
    rope_pull_ned,
    rope_turn_lead,
    saturate,
)
from gcs.loop._events import EventLog
from gcs.loop._fleet import FleetState
from gcs.loop._load_share import LoadSharing

__all__ = ["ROPE_LEAD_CARRIED_MIN", "RopeLead"]

ROPE_LEAD_CARRIED_MIN = 0.5
"""Least share of the payload's weight the thrusts must show on the ropes for the spin's rope
lead to act (carried, it is near 1; on copters without a payload, 0.0)."""


class RopeLead:
    """Adds the ropes' leads to the guidance's accelerations (see the module's docstring)."""

    def __init__(self, team: Team, guidance: Guidance, sharing: LoadSharing | None,
                 events: EventLog) -> None:
        self._team = team
        self._guidance = guidance
        self._sharing = sharing
        self._events = events
        self._pull: tuple[float, np.ndarray] | None = None  # scale, (n, 2) body-frame pulls

    def apply(self, fleet: FleetState, demand: MotionDemand, accel: np.ndarray, *,
              carrying: bool) -> np.ndarray:
        """``accel`` plus the leads of the ropes' pulls, turning with a spinning team
        (``carrying``: the payload hangs) and growing or shrinking as the ropes take or
        give up the payload; saturated again; unchanged when neither."""
        lag = self._team.config.guidance.rope_lag
        omega = self._guidance.angular_rate(demand) if carrying else 0.0
        if omega != 0.0 and lag > 0.0 and not self._ropes_pull(fleet):
            omega = 0.0
        rate = self._sharing.carried_rate if self._sharing is not None else 0.0
        if lag <= 0.0 or (omega == 0.0 and rate == 0.0):
            return accel
        scale = demand.scale
        if self._pull is None or self._pull[0] != scale:
            try:
                pull = desired_load(self._team, scale=scale).force_ned[:, :2]
            except NoHangingPointError:  # ropes too short to hang it: nothing to lead
                pull = np.zeros((fleet.n, 2))
            self._pull = (scale, np.ascontiguousarray(pull))
        heading = fit_rotation(scale * self._team.formation.positions, fleet.p_ned[:, :2])
        if heading is None:
            return accel
        pull_ned = rope_pull_ned(self._pull[1], heading)
        mass = self._team.config.airframe.mass
        lead = rope_growth_lead(pull_ned, rate, lag, mass)
        if omega != 0.0:
            lead += rope_turn_lead(pull_ned, omega, lag, mass)
        lim = self._team.config.limits
        return saturate(accel + lead, norm_max=lim.accel_norm, axis_max=lim.accel_axis)

    def _ropes_pull(self, fleet: FleetState) -> bool:
        """Whether the ropes carry the payload, as the spin's rope lead assumes: not when
        every vehicle's fresh thrust says they carry under :data:`ROPE_LEAD_CARRIED_MIN` of
        its weight (a payload left on the ground, or copters with none: the lead, sized
        for the design's pulls and with no pull to cancel, would spin the team apart).
        Unknown (no thrusts, or not fresh): assumed."""
        sharing = self._sharing
        if sharing is None or fleet.thrust is None or fleet.thrust_age is None:
            return True
        if not np.all(fleet.thrust_age <= self._team.config.safety.stale_after):
            return True
        carried = sharing.carried(fleet.thrust, fleet.tilt)
        if not carried < ROPE_LEAD_CARRIED_MIN:  # NaN: not known
            return True
        self._events.warn_once(("rope lead", 0), f"the ropes carry {max(carried, 0.0):.2f} of "
                               "the payload's weight (from the vehicles' thrusts): the spin's "
                               "rope lead (guidance.rope_lag) is off")
        return False
