"""Scenario files: the shipped ones load, a wrong step is refused naming it."""

from __future__ import annotations

from pathlib import Path

import pytest

from gcs.app import load_scenario
from gcs.common import ConfigError


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
