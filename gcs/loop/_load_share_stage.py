"""The loop's load-sharing stage: the altitude trims moved on each tick's thrusts.

The trims themselves are :class:`gcs.loop._load_share.LoadSharing`; this stage
decides, from the phase and the freshness of every vehicle's thrust, what it
learns from each tick: each one's slack-rope thrust below the pickup band's
lower half, the trims from the band's bottom up (where the ropes start to take
the payload), the rate the ropes take it at while lifting; back to zero on the
ground.
"""

from __future__ import annotations

import math

import numpy as np

from gcs.analysis import NoHangingPointError, desired_load
from gcs.config import Team
from gcs.loop._events import EventLog
from gcs.loop._fleet import FleetState
from gcs.loop._load_share import LoadSharing
from gcs.loop._phases import Phase

__all__ = ["LoadShareStage", "load_sharing"]

_CARRYING = frozenset({Phase.LIFTING, Phase.FORMATION, Phase.SETTING_DOWN})
"""Phases in which the payload may hang from the ropes (load sharing acts in them)."""
_SLACK_HOVER = frozenset({Phase.HOVER, Phase.LIFTING, Phase.FORMATION})
"""Phases whose thrusts below the taut-rope altitude are each vehicle's own weight (not
the take-off's or the landing's climb and descent)."""
_SHARE_DT_MAX = 0.5
"""Longest step of the load-sharing trims, s: a late tick does not jump them."""


def load_sharing(team: Team) -> LoadSharing | None:
    """The team's load sharing, toward the split at the desired shape; None when off, or
    when the team has no free split (three vehicles) or no hanging point."""
    fl = team.config.flight
    if not fl.load_sharing:
        return None
    try:
        target = desired_load(team).share
    except NoHangingPointError:
        return None
    sharing = LoadSharing(team.formation.positions, target,
                          vehicle_mass=team.config.airframe.mass,
                          payload_mass=team.config.payload.mass, gain=fl.load_share_gain,
                          trim_max=fl.load_share_trim_max)
    return sharing if sharing.active else None


class LoadShareStage:
    """Moves the team's load-sharing trims, tick by tick (see the module's docstring)."""

    def __init__(self, team: Team, events: EventLog) -> None:
        self._team = team
        self._events = events
        self.sharing = load_sharing(team)
        """The altitude trims that keep the payload's split as designed (None: off)."""
        self._shared_at = -math.inf

    @property
    def trims(self) -> np.ndarray | None:
        """Each vehicle's altitude trim, m (None: load sharing off)."""
        return self.sharing.trims if self.sharing is not None else None

    def update(self, now: float, fleet: FleetState, phase: Phase, scale: float) -> None:
        """Learn from this tick's thrusts while every vehicle's thrust is fresh."""
        sharing = self.sharing
        if sharing is None:
            return
        if not phase.airborne:
            sharing.reset()
            self._shared_at = -math.inf
            return
        dt, self._shared_at = min(now - self._shared_at, _SHARE_DT_MAX), now
        if fleet.thrust is None or fleet.thrust_age is None:
            sharing.observe_carried(now, None, fleet.tilt)
            return
        cfg = self._team.config
        fresh = bool(np.all(fleet.thrust_age <= cfg.safety.stale_after)
                     and np.all(np.isfinite(fleet.thrust)) and np.all(np.isfinite(fleet.tilt)))
        if fresh:  # heard again, in any phase: a later silence is said again
            self._events.unlatch(("load sharing", 0))
        # the rate the ropes take the payload at, for the pickup's rope lead (not the
        # set-down's: the payload touching down is a step the lead came too late for)
        sharing.observe_carried(now, fleet.thrust if fresh and phase is Phase.LIFTING
                                else None, fleet.tilt)
        altitude = float(np.mean(-fleet.p_ned[:, 2]))
        taut, below = self._team.taut_altitude(scale), cfg.flight.pickup_band[0]
        # every rope slack up to half the band below the taut-rope altitude: a take-off
        # that overshot into the band's lower half still leaves time to learn the slack
        if altitude < taut - below / 2 and fresh and phase in _SLACK_HOVER:
            sharing.observe_slack(dt, fleet.thrust, fleet.tilt)
        if altitude < taut - below or phase not in _CARRYING:
            return
        if fresh:
            sharing.update(dt, fleet.thrust, fleet.tilt)
            return
        silent = [vid for vid, age in zip(self._team.formation.ids, fleet.thrust_age,
                                          strict=True) if not age <= cfg.safety.stale_after]
        if silent:
            self._events.warn_once(("load sharing", 0), "load sharing held: no collective "
                                   "thrust (ATTITUDE_TARGET) from vehicle(s) "
                                   f"{', '.join(map(str, silent))}")
