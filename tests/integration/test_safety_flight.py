"""Safety rules against the real simulator: a vehicle's link cut, a vehicle killed.

The sim runs as its own process (lockstep with the GCS's clock); the control
topic of the sim breaks a vehicle on purpose, as a failing radio or a crash
would.
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from gcs.app import GcsApp
from gcs.app._scenario import Scenario, Step, play
from gcs.config import load_team
from gcs.loop import Action, Phase
from gcs.loop._safety import SafetyReason
from gcs.wire import SimMode
from tests.support.flights import break_vehicle, in_formation, sim_sleep

TEAM = load_team("configs/bebop_square.yaml")


@pytest.fixture
def flying() -> Iterator[GcsApp]:
    """The paper's team in formation flight with the payload lifted."""
    with in_formation() as app:
        yield app


def hold_sticks(app: GcsApp, seconds: float) -> None:
    end = app.clock.now() + seconds
    while app.clock.now() < end:
        app.operator.set_sticks(0.6, 0.0, 0.0, now=app.clock.now(), source="test")
        sim_sleep(app, 0.25)


def test_cut_link_freezes_the_motion_then_lands_the_team(flying: GcsApp) -> None:
    app = flying
    hold_sticks(app, 2.0)
    snap = app.runtime.snapshot
    assert snap is not None and snap.demand.forward > 0.3  # moving (stick 0.6 after expo)
    break_vehicle(app, "cut", 3)
    cut_at = app.clock.now()
    while app.runtime.snapshot.safety.events == ():
        hold_sticks(app, 0.25)
        assert app.clock.now() - cut_at < 1.5, "stale telemetry not reported"
    snap = app.runtime.snapshot
    assert snap.safety.freeze
    assert [(e.reason, e.vehicle) for e in snap.safety.events] == [(SafetyReason.STALE, 3)]
    assert snap.demand.forward == 0.0  # motion frozen although the stick is held
    assert snap.phase is Phase.FORMATION
    assert any("vehicle 3" in e.text and e.level == "warning" for e in app.runtime.events())
    # silent for longer than safety.land_after (3 s): the team lands
    hold_sticks(app, TEAM.config.safety.land_after + 1.0)
    assert app.runtime.phase in (Phase.ABORTING, Phase.LANDING, Phase.LANDED)


def test_killed_vehicle_is_reported_gone_and_the_team_lands(flying: GcsApp) -> None:
    app = flying
    break_vehicle(app, "kill", 2)
    killed_at = time.monotonic()

    def gone() -> bool:
        return any("vehicle 2 vanished" in e.text and e.level == "warning"
                   for e in app.runtime.events())

    while not gone():
        time.sleep(0.05)
        assert time.monotonic() - killed_at < 1.0, "killed vehicle not reported within 1 s"
    sim_sleep(app, TEAM.config.safety.land_after + 1.5)
    assert app.runtime.phase in (Phase.ABORTING, Phase.LANDING, Phase.LANDED)
    texts = [e.text for e in app.runtime.events()]
    assert any("vehicle 2" in t and "landing the team" in t for t in texts)


def test_abort_holds_then_lands(flying: GcsApp) -> None:
    """Repeated aborts (a held key's auto-repeat, several viewers) neither restart the hold
    nor call the landing team back into it."""
    app = flying
    hold_sticks(app, 1.0)
    app.runtime.request(Action.ABORT)
    started = app.clock.now()
    assert app.runtime.phase is Phase.ABORTING
    sim_sleep(app, 0.5)
    assert app.runtime.snapshot.demand.forward == 0.0
    hold = TEAM.config.flight.abort_hold
    while app.runtime.phase is Phase.ABORTING:  # aborts every 0.1 s all through the hold
        assert app.clock.now() - started < hold + 0.5, "repeated aborts restart the hold"
        app.runtime.request(Action.ABORT)
        sim_sleep(app, 0.1)
    assert app.clock.now() - started >= hold
    assert app.runtime.phase is Phase.LANDING
    app.runtime.request(Action.ABORT)  # landing is the abort's end: it lands on
    sim_sleep(app, 0.5)
    assert app.runtime.phase in (Phase.LANDING, Phase.LANDED)
    assert [e.text for e in app.runtime.events()].count("phase: aborting") == 1


def test_a_vehicle_leaving_offboard_freezes_then_its_landing_lands_the_team(
        flying: GcsApp) -> None:
    """As when a pilot flips one vehicle's mode switch: a real MAVLink mode command."""
    app = flying
    hold_sticks(app, 1.0)
    app.links.profiles[2].set_mode(SimMode.HOLD)
    hold_sticks(app, 0.5)
    snap = app.runtime.snapshot
    assert snap.safety.freeze and not snap.safety.land
    assert [(e.reason, e.vehicle) for e in snap.safety.events] == [(SafetyReason.MODE, 2)]
    assert snap.demand.forward == 0.0  # the stick is held, the motion frozen
    assert snap.phase is Phase.FORMATION
    assert any(e.text == "vehicle 2: in HOLD, not OFFBOARD: motion frozen"
               for e in app.runtime.events())

    app.links.profiles[2].land()
    hold_sticks(app, 0.5)
    assert app.runtime.phase in (Phase.ABORTING, Phase.LANDING, Phase.LANDED)
    assert any(e.text == "vehicle 2: coming down on its own (LAND): landing the team"
               for e in app.runtime.events())


def test_resume_brings_a_held_vehicle_back_and_the_motion_with_it(flying: GcsApp) -> None:
    """After a vehicle fell into HOLD (a gap in its setpoints, a pilot's switch), the
    operator's resume switches it back to OFFBOARD and the frozen motion goes on."""
    app = flying
    hold_sticks(app, 1.0)
    app.links.profiles[3].set_mode(SimMode.HOLD)
    hold_sticks(app, 0.5)
    assert app.runtime.snapshot.safety.freeze
    assert app.runtime.snapshot.demand.forward == 0.0
    play(Scenario(name="resume", steps=(Step(action="resume"),)), app.runtime, app.clock)
    hold_sticks(app, 0.75)
    snap = app.runtime.snapshot
    assert snap.phase is Phase.FORMATION
    assert snap.fleet.modes == ("OFFBOARD",) * 4
    assert not snap.safety.freeze and snap.demand.forward > 0.0  # moving again
    texts = [e.text for e in app.runtime.events()]
    assert "resume: vehicle 3 back in OFFBOARD" in texts
    # nothing to resume: said so, nothing sent
    play(Scenario(name="again", steps=(Step(action="resume"),)), app.runtime, app.clock)
    assert app.runtime.events()[-1].text == \
        "resume: every flying vehicle is in its streaming mode already"
