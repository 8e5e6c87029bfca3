"""A wrong team config is refused with one line naming the file, the field and the fault."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml

from gcs.analysis import analyze
from gcs.config import load_team
from gcs.config._team import ConfigError
from gcs.loop import load_gamepad_config
from tests.support.commands import gcs_here
from vehicles import BEBOP2, load_airframe

SQUARE = Path("configs/bebop_square.yaml")

Mutation = Callable[[dict[str, Any]], object]


def write(tmp_path: Path, mutate) -> Path:  # type: ignore[no-untyped-def]
    data = yaml.safe_load(SQUARE.read_text())
    data["airframe"] = str(Path("configs/airframes/bebop2.yaml").resolve())
    mutate(data)
    path = tmp_path / "team.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def refused(tmp_path: Path, mutate, field: str, words: str) -> str:  # type: ignore[no-untyped-def]
    path = write(tmp_path, mutate)
    with pytest.raises(ConfigError) as info:
        load_team(path)
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith(f"{path}: {field}"), text
    assert words in text, text
    return text


def test_the_shipped_configs_load() -> None:
    for path in Path("configs").glob("bebop_*.yaml"):
        load_team(path)
    load_gamepad_config(Path("configs/gamepad.yaml"))


def edge(k: int, value: list[float]) -> Mutation:
    """Replace the square's edge k."""
    return lambda d: d["edges"].__setitem__(k, value)


#: One config mistake of each kind: the change to the square, the field named, the fault.
MISTAKES: dict[str, tuple[Mutation, str, str]] = {
    "missing field": (lambda d: d["guidance"].pop("c2"), "guidance.c2", "missing"),
    "wrong type": (lambda d: d["guidance"].update(c1="fast"), "guidance.c1",
                   "expected a number, got a string"),
    "negative mass": (lambda d: d["payload"].update(mass=-0.4), "payload.mass",
                      "must be greater than 0, got -0.4"),
    "distance off the positions": (edge(1, [2, 4, 1.2]), "edges[1].distance",
                                   "does not fit the positions"),
    "unknown vehicle": (edge(3, [1, 7]), "edges[3].head", "unknown vehicle id 7"),
    "not rigid": (lambda d: d.update(edges=[[1, 2], [2, 3], [3, 4], [4, 1]]), "edges",
                  "not rigid"),  # the square's sides without its diagonals: it shears
}


@pytest.mark.parametrize("mistake", MISTAKES)
def test_a_config_mistake_is_refused(tmp_path: Path, mistake: str) -> None:
    refused(tmp_path, *MISTAKES[mistake])


@pytest.mark.parametrize("mistake", MISTAKES)
def test_gcs_analyze_refuses_a_config_mistake_in_one_line_with_status_2(
        tmp_path: Path, mistake: str) -> None:
    """The command line, not only load_team: one stderr line naming file and field, exit 2."""
    mutate, field, words = MISTAKES[mistake]
    path = write(tmp_path, mutate)
    out = gcs_here("analyze", str(path))
    assert out.returncode == 2, out.stdout + out.stderr
    assert out.stdout == ""
    [line] = out.stderr.splitlines()
    assert out.stderr == line + "\n"
    assert line.startswith(f"gcs analyze: error: {path}: {field}"), line
    assert words in line, line


def test_negative_airframe_mass_inline(tmp_path: Path) -> None:
    def inline(d: dict) -> None:
        d["airframe"] = {**yaml.safe_load(BEBOP2.read_text()), "mass": -1.0}
    refused(tmp_path, inline, "airframe.mass", "greater than 0")


@pytest.mark.parametrize("missing", ["mass", "thrust_reference", "inertia", "drag_coefficient"])
def test_an_airframe_file_missing_a_field_is_refused(tmp_path: Path, missing: str) -> None:
    """No paper figure stands in for a forgotten one (``{name: mystery}`` gave 5.230 N)."""
    data = yaml.safe_load(BEBOP2.read_text())
    data.pop(missing)
    frame = tmp_path / "mystery.yaml"
    frame.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError) as info:
        load_airframe(frame)
    assert str(info.value) == f"{frame}: {missing}: missing required field"
    with pytest.raises(ConfigError) as info:  # and through the team file that names it
        load_team(write(tmp_path, lambda d: d.update(airframe=str(frame))))
    assert str(info.value) == f"{frame}: {missing}: missing required field"


def test_an_airframe_with_only_a_name_is_refused(tmp_path: Path) -> None:
    frame = tmp_path / "mystery.yaml"
    frame.write_text("name: mystery\n")
    with pytest.raises(ConfigError, match=r"^\S*mystery.yaml: mass: missing required field$"):
        load_airframe(frame)


@pytest.mark.parametrize("section, missing", [
    ("guidance", "c1"), ("guidance", "c2"), ("guidance", "rate_hz"),
    ("guidance", "max_speed"), ("guidance", "max_rotation_disagreement"),
    ("limits", "bank_deg"), ("limits", "accel_norm"), ("limits", "accel_axis"),
    ("payload", "mass"), ("payload", "rope_length"),
    ("analysis", "max_distance_error"), ("analysis", "design_rope_angle_deg"),
])
def test_a_missing_gain_or_physical_field_is_refused(tmp_path: Path, section: str,
                                                     missing: str) -> None:
    text = refused(tmp_path, lambda d: d[section].pop(missing), f"{section}.{missing}",
                   "missing required field")
    assert text.endswith(f"{section}.{missing}: missing required field")


def test_a_missing_analysis_section_is_refused(tmp_path: Path) -> None:
    refused(tmp_path, lambda d: d.pop("analysis"), "analysis", "missing required field")


def test_every_team_file_states_its_gains_and_physics() -> None:
    """The shipped teams load and analyse from their own figures only."""
    for path in sorted(Path("configs").glob("bebop_*.yaml")):
        raw = yaml.safe_load(path.read_text())
        for section, names in (("guidance", ("c1", "c2", "rate_hz", "max_speed",
                                              "max_rotation_disagreement")),
                               ("analysis", ("max_distance_error", "design_rope_angle_deg"))):
            assert set(names) <= set(raw[section]), (path, section)
        assert analyze(load_team(path)).ok


def test_unknown_field(tmp_path: Path) -> None:
    refused(tmp_path, lambda d: d["limits"].update(bank_degree=20), "limits.bank_degree",
            "unknown field")


def test_collinear_shape_is_degenerate_not_short_of_edges(tmp_path: Path) -> None:
    def line(d: dict) -> None:
        d["vehicles"] = [{"id": k + 1, "position": [float(k), 0.0]} for k in range(4)]
        d["edges"] = [[i, j] for i in range(1, 5) for j in range(i + 1, 5)]  # complete
    text = refused(tmp_path, line, "edges", "the shape is degenerate: the vehicles are collinear")
    assert "add edges" not in text
    assert "place them off a line" in text


def test_duplicate_vehicle_id(tmp_path: Path) -> None:
    refused(tmp_path, lambda d: d["vehicles"][2].update(id=1), "vehicles", "appears twice")


def test_distances_that_cannot_be_realised(tmp_path: Path) -> None:
    def triangle_inequality(d: dict) -> None:
        for v in d["vehicles"]:
            v.pop("position")
        d["vehicles"] = d["vehicles"][:3]
        d["edges"] = [[1, 2, 1.0], [2, 3, 1.0], [3, 1, 3.0]]
    refused(tmp_path, triangle_inequality, "edges[", "cannot be realised in the plane")


def test_some_positions_missing(tmp_path: Path) -> None:
    refused(tmp_path, lambda d: d["vehicles"][1].pop("position"), "vehicles[1].position",
            "missing")


def test_bad_edge_shape(tmp_path: Path) -> None:
    def bad(d: dict) -> None:
        d["edges"][0] = [1]
    refused(tmp_path, bad, "edges[0]", "expected [tail, head]")


def test_missing_airframe_file(tmp_path: Path) -> None:
    refused(tmp_path, lambda d: d.update(airframe="nowhere.yaml"), "airframe", "not found")


def test_out_of_range_bank(tmp_path: Path) -> None:
    refused(tmp_path, lambda d: d["limits"].update(bank_deg=95), "limits.bank_deg",
            "less than 90")


def test_scale_range_must_bracket_one(tmp_path: Path) -> None:
    refused(tmp_path, lambda d: d["guidance"].update(scale_min=1.2), "guidance",
            "must bracket 1")


def test_setpoint_rate_must_be_a_multiple_of_the_guidance_rate(tmp_path: Path) -> None:
    refused(tmp_path, lambda d: d["guidance"].update(setpoint_rate_hz=10.0), "guidance",
            "setpoint_rate_hz (10 Hz) must be a whole multiple of guidance.rate_hz (4 Hz)")
    refused(tmp_path, lambda d: d["guidance"].update(setpoint_rate_hz=2.0), "guidance",
            "whole multiple")


def test_malformed_yaml(tmp_path: Path) -> None:
    path = tmp_path / "broken.yaml"
    path.write_text("name: x\nvehicles: [1, 2\n")
    with pytest.raises(ConfigError, match=r"broken.yaml: line \d+: invalid YAML"):
        load_team(path)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read file"):
        load_team(tmp_path / "absent.yaml")
