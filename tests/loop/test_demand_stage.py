"""The demand stage (gcs.loop._demand_stage): the operator's motion flown only in formation,
unfrozen and switched on; fenced where the team can be placed; the guidance's prediction
following the slowest link's round trip, capped."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gcs.config import load_team
from gcs.guidance import Guidance, MotionDemand
from gcs.loop import LINK_DELAY_CAP_S, OperatorSnapshot, Phase
from gcs.loop._demand_stage import DemandStage
from gcs.loop._events import EventLog
from gcs.loop._safety import SafetyVerdict
from tests.support.scripted_autopilot import HOVER_THRUST, SQUARE, fleet_state

TEAM = load_team(str(SQUARE))
FLOWING = SafetyVerdict(freeze=False, land=False, events=())
FROZEN = SafetyVerdict(freeze=True, land=False, events=())


@dataclass
class _Link:
    rtt_s: float | None = None


@dataclass
class _Profile:
    link: _Link


def _op(*, on: bool = True, scale: float = 1.2) -> OperatorSnapshot:
    return OperatorSnapshot(demand=MotionDemand(forward=0.5, rotate=0.3, scale=scale),
                            altitude=1.5, altitude_target=1.5, scale_target=scale,
                            guidance_on=on, source="test")


def _stage(links: list[_Link], *, follow: bool) -> tuple[DemandStage, Guidance, EventLog]:
    guidance, events = Guidance.from_team(TEAM), EventLog(lambda: 0.0, None)
    profiles = [_Profile(link) for link in links]
    return DemandStage(TEAM, guidance, profiles, truth_source=None,  # type: ignore[arg-type]
                       events=events, follow_link_delay=follow), guidance, events


def test_the_operators_motion_is_flown_only_in_formation_unfrozen_and_switched_on() -> None:
    flown = DemandStage.motion(Phase.FORMATION, FLOWING, _op())
    assert flown == (True, _op().demand)
    for phase, verdict, on in ((Phase.HOVER, FLOWING, True), (Phase.FORMATION, FROZEN, True),
                               (Phase.FORMATION, FLOWING, False)):
        moving, demand = DemandStage.motion(phase, verdict, _op(on=on))
        assert not moving and demand == MotionDemand(scale=1.2)  # the scale is kept


def test_a_frozen_or_unplaced_team_is_not_fenced_and_a_placed_one_is() -> None:
    stage, _, _ = _stage([_Link()] * 4, follow=False)
    fleet = fleet_state(TEAM.formation.positions, HOVER_THRUST)
    demand = MotionDemand(forward=1.0)
    assert stage.limit(fleet, demand, FROZEN) == (demand, None)
    fenced, fence = stage.limit(fleet, demand, FLOWING)
    assert fence is not None and fenced == fence.demand


def test_the_prediction_follows_the_slowest_links_round_trip_up_to_its_cap() -> None:
    links = [_Link(0.02), _Link(0.1), _Link(None), _Link(0.05)]
    stage, guidance, _ = _stage(links, follow=True)
    base = guidance.lead
    stage.limit(fleet_state(TEAM.formation.positions, HOVER_THRUST), MotionDemand(), FROZEN)
    assert np.isclose(guidance.lead, base + 0.1)
    links[1].rtt_s = 10.0
    for _ in range(40):  # the median of the recent round trips
        stage.limit(fleet_state(TEAM.formation.positions, HOVER_THRUST), MotionDemand(), FROZEN)
    assert np.isclose(guidance.lead, base + LINK_DELAY_CAP_S)


def test_in_lockstep_the_prediction_stays_the_guidances_own() -> None:
    stage, guidance, _ = _stage([_Link(0.2)] * 4, follow=False)
    base = guidance.lead
    stage.limit(fleet_state(TEAM.formation.positions, HOVER_THRUST), MotionDemand(), FROZEN)
    assert guidance.lead == base
