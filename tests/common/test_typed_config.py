"""A team changed in memory travels to another process (the simulator) as it is: its
plain form (:func:`gcs.common.to_mapping`) builds the same config back, checked as its
file would be, relative paths still from the file's directory."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from gcs.common import ConfigError, to_mapping
from gcs.config import load_team
from tests.support.paths import ROOT

TEAMS = sorted([*ROOT.glob("configs/bebop_*.yaml"), *ROOT.glob("tests/data/bebop_*.yaml")])


@pytest.mark.parametrize("path", TEAMS, ids=lambda p: p.name)
def test_every_shipped_team_comes_back_from_its_plain_form(path: Path) -> None:
    team = load_team(path)
    again = load_team(path, mapping=json.loads(json.dumps(to_mapping(team.config))))
    assert again.config == team.config and again.source == team.source
    assert (again.formation.positions == team.formation.positions).all()


def test_a_change_in_memory_comes_back_and_a_wrong_one_is_refused_as_in_a_file() -> None:
    path = ROOT / "configs" / "bebop_square.yaml"
    team = load_team(path)
    payload = dataclasses.replace(team.config.payload, mass=0.2, rope_lengths=(1.0, 1.1, 1.1, 1.1),
                                  rope_length=1.1)
    changed = dataclasses.replace(team.config, payload=payload)
    assert load_team(path, mapping=to_mapping(changed)).config.payload == payload
    wrong = to_mapping(dataclasses.replace(changed, payload=dataclasses.replace(
        payload, rope_length=1.2)))  # not the longest of rope_lengths
    with pytest.raises(ConfigError, match=r"bebop_square.yaml: payload.rope_length: "):
        load_team(path, mapping=wrong)
