"""Phase transitions, scenario files and metric definitions."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gcs.app import load_scenario
from gcs.common import ConfigError
from gcs.flightlog import FlightMetrics
from gcs.flightlog._metrics import swing_angle
from gcs.loop import Action, Phase, PhaseError
from gcs.loop._phases import next_phase


def test_normal_flight_sequence() -> None:
    phase = Phase.READY
    for action, want in ((Action.ARM, Phase.ARMED), (Action.TAKEOFF, Phase.TAKING_OFF)):
        phase = next_phase(phase, action)
        assert phase is want
    assert next_phase(Phase.HOVER, Action.LIFT) is Phase.LIFTING
    assert next_phase(Phase.FORMATION, Action.SET_DOWN) is Phase.SETTING_DOWN
    assert next_phase(Phase.HOVER, Action.LAND) is Phase.LANDING


def test_refused_actions_say_why() -> None:
    with pytest.raises(PhaseError, match="cannot lift while armed"):
        next_phase(Phase.ARMED, Action.LIFT)
    with pytest.raises(PhaseError, match="cannot take off while connect"):
        next_phase(Phase.CONNECT, Action.TAKEOFF)


def test_resume_keeps_the_phase_and_only_applies_while_streaming_in_flight() -> None:
    for phase in Phase:
        if phase in (Phase.HOVER, Phase.LIFTING, Phase.FORMATION, Phase.SETTING_DOWN):
            assert next_phase(phase, Action.RESUME) is phase
        else:
            with pytest.raises(PhaseError, match=f"cannot resume while {phase.text}"):
                next_phase(phase, Action.RESUME)


def test_abort_is_possible_whenever_something_can_fly() -> None:
    """It holds then lands from any phase but its own two: aborting and landing stay."""
    for phase in Phase:
        if phase in (Phase.CONNECT, Phase.READY, Phase.LANDED):
            with pytest.raises(PhaseError):
                next_phase(phase, Action.ABORT)
        elif phase in (Phase.ABORTING, Phase.LANDING):
            assert next_phase(phase, Action.ABORT) is phase
        else:
            assert next_phase(phase, Action.ABORT) is Phase.ABORTING


def test_paper_scenario_loads() -> None:
    s = load_scenario("configs/scenarios/paper_flight.yaml")
    assert s.steps[0].action == "arm" and s.steps[-1].action == "land"
    assert any(step.sticks is not None and step.sticks.rotate for step in s.steps)


def test_scenario_errors_name_the_step(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nsteps:\n  - {action: arm}\n  - {action: jump}\n")
    with pytest.raises(ConfigError, match=r"bad.yaml: steps\[1\]: action: unknown 'jump'"):
        load_scenario(bad)
    bad.write_text("name: x\nsteps:\n  - {wait: 1, scale: 1.1}\n")
    with pytest.raises(ConfigError, match=r"steps\[0\]: a step does exactly one thing"):
        load_scenario(bad)
    bad.write_text("name: x\nsteps:\n  - {sticks: {forward: 2}, duration: 1}\n")
    with pytest.raises(ConfigError, match=r"steps\[0\].sticks.forward: must be at most 1"):
        load_scenario(bad)


def test_swing_angle() -> None:
    vehicles = np.array([[0.5, 0.5, -2.0], [-0.5, 0.5, -2.0], [-0.5, -0.5, -2.0],
                         [0.5, -0.5, -2.0]])
    assert swing_angle(vehicles, np.array([0.0, 0.0, -1.0])) == pytest.approx(0.0)
    assert swing_angle(vehicles, np.array([1.0, 0.0, -1.0])) == pytest.approx(np.pi / 4)


def test_metrics_count_only_flown_phases() -> None:
    m = FlightMetrics()
    kw = {"tilt": np.zeros(4), "accel_cmd": np.zeros((4, 2)), "vehicles_true": None,
          "payload": None, "rope_tension": None}
    m.add_tick(0.0, Phase.TAKING_OFF, distance_errors=np.array([0.5]), **kw)
    m.add_tick(0.25, Phase.FORMATION, distance_errors=np.array([0.1, -0.2]), **kw)
    m.add_tick(0.5, Phase.HOVER, distance_errors=np.array([0.05]), **kw)
    assert m.worst_distance_error == pytest.approx(0.2)
    assert m.worst_distance_error_by_phase == {"formation": 0.2, "hover": 0.05}
    assert m.duration == pytest.approx(0.5)
    assert m.to_json()["phases"] == ["taking off", "formation", "hover"]
