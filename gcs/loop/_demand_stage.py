"""The loop's demand stage: what the operator asks of the team this tick, and what it may fly.

The operator's motion is flown only in formation, when no safety rule froze it
and the guidance is switched on; the geofence then limits it
(:mod:`gcs.loop._geofence`). Over a radio the guidance predicts one link round
trip further (:meth:`DemandStage.follow_link_delay`).
"""

from __future__ import annotations

import collections
from collections.abc import Callable, Sequence

import numpy as np

from gcs.config import Team
from gcs.formation import fit_rotation
from gcs.guidance import Guidance, MotionDemand
from gcs.link import AutopilotProfile
from gcs.loop._events import EventLog
from gcs.loop._fleet import FleetState
from gcs.loop._geofence import FenceVerdict, fence_demand
from gcs.loop._operator import OperatorSnapshot
from gcs.loop._phases import Phase
from gcs.loop._safety import SafetyVerdict
from gcs.wire import SimTruth

__all__ = ["LINK_DELAY_CAP_S", "DemandStage"]

LINK_DELAY_CAP_S = 0.25
"""Largest round trip the guidance's prediction horizon follows, s: beyond it no lead saves
the paper's gains at 4 Hz (tests/guidance/test_link_delay.py)."""


class DemandStage:
    """The operator's demand, frozen, fenced or flown (see the module's docstring).

    Args:
        follow_link_delay: lengthen the guidance's prediction by the links' round trip
            (not in lockstep, where the simulator waits for the setpoints: no delay,
            and a wall-time figure would make runs differ).
    """

    def __init__(self, team: Team, guidance: Guidance, profiles: Sequence[AutopilotProfile], *,
                 truth_source: Callable[[], SimTruth | None] | None, events: EventLog,
                 follow_link_delay: bool) -> None:
        self._team = team
        self._guidance = guidance
        self._links = [p.link for p in profiles]
        self._truth_source = truth_source
        self._events = events
        self.follow_link_delay = follow_link_delay
        self._base_lead = guidance.lead
        self._rtts: collections.deque[float] = collections.deque(maxlen=40)
        self._fence_text = ""

    @staticmethod
    def motion(phase: Phase, verdict: SafetyVerdict,
               op: OperatorSnapshot) -> tuple[bool, MotionDemand]:
        """Whether the operator's motion is flown this tick, and the demand the guidance
        gets (frozen: no motion, the operator's scale)."""
        moving = phase is Phase.FORMATION and not verdict.freeze and op.guidance_on
        return moving, op.demand if moving else MotionDemand(scale=op.demand.scale)

    def limit(self, fleet: FleetState, demand: MotionDemand,
              verdict: SafetyVerdict) -> tuple[MotionDemand, FenceVerdict | None]:
        """The demand to fly while streaming: fenced where the team can be placed and no
        rule froze it (the fence's verdict; None: not applied)."""
        if self.follow_link_delay:
            self._follow_link_delay()
        if verdict.freeze or not fleet.located:
            return demand, None
        fence = self._fence(fleet, demand)
        return fence.demand, fence

    def _follow_link_delay(self) -> None:
        """The guidance predicts the distance errors half a period ahead, the hold's delay;
        over a radio the positions are a downlink old and the setpoints act an uplink
        late, so the prediction goes one round trip further (median of the last ten
        seconds of the slowest link's TIMESYNC): at 4 Hz with the paper's gains, a
        delayed link otherwise makes the shape's stiffest mode oscillate."""
        rtts = [r for r in (link.rtt_s for link in self._links) if r is not None]
        if rtts:
            self._rtts.append(max(rtts))
        if self._rtts:
            delay = min(float(np.median(self._rtts)), LINK_DELAY_CAP_S)
            self._guidance.lead = self._base_lead + delay

    def _fence(self, fleet: FleetState, demand: MotionDemand) -> FenceVerdict:
        """The demand limited by the geofence (the payload counts where it is known)."""
        p = fleet.p_ned[:, :2]
        heading = fit_rotation(demand.scale * self._team.formation.positions, p)
        truth = self._truth_source() if self._truth_source is not None else None
        points = p if truth is None else np.vstack([p, np.array(truth.payload_p_ned[:2])])
        fence = fence_demand(self._team.config.safety, demand, heading=heading, points=points,
                             velocity=fleet.v_ned[:, :2].mean(axis=0),
                             altitude=-fleet.p_ned[:, 2], max_speed=self._guidance.max_speed,
                             c1=self._guidance.c1)
        text = fence.text + (" (above the ceiling)" if fence.above else "")
        if text and text != self._fence_text:
            self._events.add("warning", text)
        self._fence_text = text
        return fence
