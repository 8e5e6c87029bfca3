"""Checks before arming against the real simulator, in lockstep (:class:`gcs.testing.SimTeam`).

The simulated vehicles answer the parameter protocol as PX4; their
``MPC_TILTMAX_AIR`` is the onboard bank limit (roll and pitch each, as the
config's ``limits.bank_deg``). The shipped pair (20 and 20 degrees) arms; a
vehicle whose limit another ground station raised to 30 degrees is shown on the
ready team's snapshot before anyone presses ARM, and then refused at the arm,
unless the team file lets the GCS set it back (read back from the simulator).
"""

from __future__ import annotations

import dataclasses

import pytest

from gcs.config import Team, load_team
from gcs.loop import Phase
from gcs.testing import FlightError
from tests.support.flights import RAISED, TOO_STEEP, prearm, ready_with_vehicle_3_raised
from tests.support.flights import SQUARE_FILE as SQUARE


def square(**limits: object) -> Team:
    """The paper's square with ``limits`` changed."""
    team = load_team(SQUARE)
    return dataclasses.replace(team, config=dataclasses.replace(
        team.config, limits=dataclasses.replace(team.config.limits, **limits)))


def test_a_simulator_banking_beyond_the_limit_is_shown_while_ready_and_refused(
        sim_team) -> None:  # type: ignore[no-untyped-def]
    team = sim_team(SQUARE, seed=1)
    ready_with_vehicle_3_raised(team)
    shown = prearm(team)
    assert len(shown) == 1 and shown[0].startswith(TOO_STEEP), shown
    assert team.phase is Phase.READY

    team.scale(0.7)  # the desired shape shrinks: the vehicles stand 0.21 m out of it
    team.wait(8.0)
    shown = prearm(team)
    print("ready, at scale 0.7:", *shown, sep="\n  ")
    assert shown[-1].startswith(TOO_STEEP) and len(shown) > 1, shown
    assert all("from its place in the team's shape" in line for line in shown[:-1]), shown
    team.scale(1.0)
    team.wait(8.0)

    with pytest.raises(FlightError) as refused:
        team.arm()
    text = str(refused.value)
    assert f"arm failed: checks before arming failed: {TOO_STEEP}" in text, text
    assert text.count("vehicle ") == 1, text
    snap = team.app.loop.snapshot
    assert snap is not None and snap.phase is Phase.READY and not snap.fleet.armed.any()
    assert team.app.loop.profiles[3].tilt_limit_deg() == RAISED  # nothing written


def test_the_gcs_sets_the_simulators_bank_limit_when_asked(
        sim_team) -> None:  # type: ignore[no-untyped-def]
    team = sim_team(square(autopilot_tilt="set"), seed=1)
    ready_with_vehicle_3_raised(team)
    assert prearm(team) == ()  # the arm will set it: nothing to refuse
    team.arm()
    assert team.phase is Phase.ARMED
    texts = [e.text for e in team.events]
    assert ("vehicle 3: tilt limit MPC_TILTMAX_AIR set from 30 to 20 degrees "
            "(limits.bank_deg), read back") in texts, texts
    assert not any("tilt limit" in t and "vehicle 3" not in t for t in texts), texts
    assert team.app.loop.profiles[3].tilt_limit_deg() == 20.0  # the simulator's own answer
