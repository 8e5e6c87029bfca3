"""The worst-case analysis against the paper's equations and figures."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import pytest
import yaml

from gcs.analysis import analyze
from gcs.analysis._forces import rope_pull
from gcs.config import load_team
from tests.support.commands import gcs_here, run_gcs

SQUARE = "configs/bebop_square.yaml"
G = 9.80665


@pytest.fixture(scope="module")
def square():  # type: ignore[no-untyped-def]
    return analyze(load_team(SQUARE))


def test_paper_figures_within_one_percent(square) -> None:  # type: ignore[no-untyped-def]
    assert square.vertical_load == pytest.approx(5.22, rel=0.01)
    assert square.max_tilt == pytest.approx(0.62, rel=0.01)
    assert square.horizontal_force == pytest.approx(2.18, rel=0.01)
    assert square.gain_terms["c1_speed"] == pytest.approx(0.17, rel=0.01)
    assert square.gain_terms["c2_distance"] == pytest.approx(0.55 * 1.7, rel=0.01)
    assert square.gain_terms["mu_rotation"] == pytest.approx(0.2 * 2, rel=0.01)
    assert square.gain_lhs <= square.max_accel_axis
    assert square.ok


def test_paper_acceleration_chain(square) -> None:  # type: ignore[no-untyped-def]
    """(F_h - M g / 3) / m and its 45-degree component, exact and as the paper rounds.

    The paper rounds F_h = 6.4 sin 20 deg = 2.189 N down to 2.18 N before the
    subtraction, which amplifies the 0.4 % rounding to 1.1 %: exact arithmetic
    gives 2.203 and 1.558 m/s^2, 1.07 % and 1.17 % above its 2.18 and 1.54. The
    analysis keeps the exact arithmetic (no rounding in the code); this test
    pins the formula, and checks the paper's two figures at 1 % against the
    paper's own arithmetic: the same analysis with F_h rounded down to 2.18 N.
    """
    m = M = 0.4
    f_h = 6.4 * math.sin(math.radians(20.0))
    assert square.horizontal_force == pytest.approx(f_h, rel=1e-12)
    assert square.rope_pull_design == pytest.approx(M * G / 3, rel=1e-9)
    assert square.max_accel == pytest.approx((f_h - M * G / 3) / m, rel=1e-12)
    assert square.max_accel_axis == pytest.approx((f_h - M * G / 3) / m * math.sqrt(0.5),
                                                  rel=1e-12)

    rounded_f_h = math.floor(square.horizontal_force * 100.0) / 100.0  # the paper's 2.18 N
    assert rounded_f_h == 2.18
    team = load_team(SQUARE)
    frame = dataclasses.replace(team.config.airframe,
                                thrust_reference=rounded_f_h / math.sin(team.config.limits.bank))
    paper = analyze(dataclasses.replace(
        team, config=dataclasses.replace(team.config, airframe=frame)))
    assert paper.horizontal_force == pytest.approx(2.18, rel=1e-12)
    assert paper.max_accel == pytest.approx(2.18, rel=0.01)
    assert paper.max_accel_axis == pytest.approx(1.54, rel=0.01)


def test_equilibrium_tension_is_eq_T(square) -> None:  # type: ignore[no-untyped-def]
    l, d2 = math.sqrt(1.25), math.sqrt(2.0)
    want = (0.4 * G / 4) * l / math.sqrt(l**2 - d2**2 / 4)
    assert square.equilibrium_tension == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("config, n, mass, rope, r", [
    # an equilateral triangle of side 1.2 m: its circumradius
    ("configs/bebop_triangle.yaml", 3, 0.25, 1.2, 1.2 / math.sqrt(3)),
    # a regular hexagon of radius 1 m (its positions are given to 6 decimals)
    ("configs/bebop_hexagon.yaml", 6, 0.3, 1.6, 1.0),
])
def test_equilibrium_tension_is_eq_T_for_n_vehicles(config: str, n: int, mass: float,
                                                    rope: float, r: float) -> None:
    """Eq. T beyond the square: each of the n ropes holds M g / n, its vehicle r from the
    payload under the centroid. For the square r is half the diagonal (eq. T's d2 / 2),
    not half an edge; here the circumradius of the regular polygon.
    """
    a = analyze(load_team(config))
    assert a.vehicles == n
    assert a.equilibrium_tension == pytest.approx(
        (mass * G / n) * rope / math.sqrt(rope**2 - r**2), rel=1e-6)
    assert a.equilibrium_rope_angle == pytest.approx(math.asin(r / rope), rel=1e-6)


def test_eq_Th_as_written_and_where_the_papers_bound_holds(square) -> None:  # type: ignore[no-untyped-def]
    l = math.sqrt(1.25)
    w = 0.4 * G / 3
    # at the 2 m the paper names, the equation gives twice its stated bound
    assert square.worst_edge == pytest.approx(2.0)
    assert square.rope_pull_worst_edge == pytest.approx(w * 2.0, rel=1e-9)
    assert rope_pull(w, l, 2.0) == pytest.approx(2 * w)
    # the bound M g / 3 holds where the rope is at 45 degrees: ||z2|| = l sqrt 2
    assert square.rope_pull_bound_span == pytest.approx(l * math.sqrt(2))
    assert rope_pull(w, l, l * math.sqrt(2)) == pytest.approx(w)
    assert rope_pull(w, l, 2 * l) == math.inf


def test_safe_deformation_leaves_the_configured_acceleration(square) -> None:  # type: ignore[no-untyped-def]
    w = 0.4 * G / 3
    l = math.sqrt(1.25)
    at_bound = rope_pull(w, l, square.safe_span)
    assert square.horizontal_force - at_bound == pytest.approx(0.4 * 2.18, rel=1e-9)
    assert square.safe_deformation == pytest.approx(square.safe_span - math.sqrt(2))
    assert 0 < square.safe_deformation < 0.3


@pytest.mark.parametrize("name", ["bebop_triangle", "bebop_hexagon"])
def test_other_teams_pass(name: str) -> None:
    result = analyze(load_team(f"configs/{name}.yaml"))
    assert result.ok, result.violations
    assert result.vehicles in (3, 6)


def test_cli_table_and_json() -> None:
    out = run_gcs("analyze", SQUARE)
    assert out.returncode == 0, out.stderr
    assert "eq. max" in out.stdout and "result: OK" in out.stdout
    out = run_gcs("analyze", SQUARE, "--json")
    assert out.returncode == 0
    data = json.loads(out.stdout)
    assert data["ok"] is True
    assert data["vertical_load_N"] == pytest.approx(5.22, rel=0.01)
    # The paper's 2.18 and 1.54 m/s^2 from the shipped config's own arithmetic. 1 % is
    # out of reach: the paper truncates F_h = 2.189 N to 2.18 N before subtracting
    # M g / 3 = 1.308 N, which turns its 0.4 % into 1.07 % and 1.17 % (exactly 2.203
    # and 1.558). 1.2 % holds them, and a regression beyond that rounding shows.
    assert data["max_guidance_accel_m_s2"] == pytest.approx(2.18, rel=0.012)
    assert data["max_guidance_accel_axis_m_s2"] == pytest.approx(1.54, rel=0.012)


#: The documented --json keys (README, "Worst-case analysis"); nested mappings as dicts.
JSON_KEYS: dict[str, object] = {
    "team": None, "vehicles": None, "gravity_m_s2": None, "payload_share": None,
    "equilibrium_tension_N": None, "equilibrium_rope_angle_rad": None,
    "vertical_load_N": None, "max_tilt_rad": None, "bank_limit_rad": None,
    "horizontal_force_N": None,
    "rope_pull": {"nominal_span_m": None, "nominal_N": None, "design_rope_angle_rad": None,
                  "design_span_m": None, "design_N": None, "bound_N": None,
                  "bound_span_m": None, "worst_edge_m": None, "worst_edge_N": None},
    "max_guidance_accel_m_s2": None, "max_guidance_accel_axis_m_s2": None,
    "gain_condition": {
        "terms_m_s2": {"c1_speed": None, "c2_distance": None, "mu_rotation": None},
        "coefficients": {"c1": None, "c2": None, "mu_r": None, "speed_error_m_s": None,
                         "distance_error_m": None, "kappa": None, "worst_edge_m": None},
        "lhs_m_s2": None, "rhs_m_s2": None, "ok": None},
    "configured_limits": {"accel_norm_m_s2": None, "accel_axis_m_s2": None},
    "safe_deformation": {"span_m": None, "margin_m": None},
    "static_load": {"rope_lengths_m": None, "taut": None, "tension_N": None, "vertical_N": None,
                    "horizontal_N": None, "share": None, "payload_offset_m": None,
                    "hang_depth_m": None, "statically_determinate": None,
                    "assumed_share": None, "worst_share": None, "worst_vehicle": None,
                    "position_error_m": None, "hold_stiffness_N_m": None,
                    "worst_tension_N": None, "worst_horizontal_N": None,
                    "worst_vertical_load_N": None, "design_share": None, "design_basis": None,
                    "even_rope_lengths_m": None, "accel_m_s2": None, "accel_share": None,
                    "accel_vehicle": None, "accel_tension_N": None},
    "largest_payload_kg": None,
    "lift": {"altitude_m": None, "ceiling_m": None},
    "scales_flown": {"min": None, "max": None},
    "shape_hold": dict.fromkeys(["weakest_stiffness", "disturbance_m_s2", "drift_error_m",
                                 "new_edges", "new_stiffness"]),
    "violations": None, "warnings": None, "ok": None,
}
VIOLATION_KEYS = ["term", "message", "fixes"]


def key_tree(data: object) -> object:
    """The keys of nested mappings, with None at the leaves (lists are leaves)."""
    if isinstance(data, dict):
        return {k: key_tree(v) for k, v in data.items()}
    return None


def test_json_keys_are_exactly_the_documented_tree(tmp_path: Path) -> None:
    for path in (SQUARE, str(greedy(tmp_path, c1=0.8, accel_norm=2.5))):
        data = json.loads(gcs_here("analyze", path, "--json").stdout)
        assert key_tree(data) == JSON_KEYS
        assert list(data) == list(JSON_KEYS)  # order too: a stable object
        for violation in data["violations"]:
            assert list(violation) == VIOLATION_KEYS
            assert all(isinstance(v, float) for v in violation["fixes"].values())
        assert all(isinstance(w, str) for w in data["warnings"])
    assert len(data["violations"]) == 2


def greedy(tmp_path: Path, **changes: float) -> Path:
    """The square with some guidance or limits fields changed, as a file."""
    data = yaml.safe_load(Path(SQUARE).read_text())
    data["airframe"] = str(Path("configs/airframes/bebop2.yaml").resolve())
    for name, value in changes.items():
        section = "limits" if name in ("bank_deg", "accel_norm", "accel_axis") else "guidance"
        data[section][name] = value
    path = tmp_path / ("greedy-" + "-".join(changes) + ".yaml")
    path.write_text(yaml.safe_dump(data))
    return path


def violated(path: Path) -> list[dict[str, object]]:
    """Run the CLI on a config that must fail; its violations (checked in text and JSON)."""
    text = gcs_here("analyze", str(path))
    assert text.returncode == 1, text.stdout + text.stderr
    out = gcs_here("analyze", str(path), "--json")
    assert out.returncode == 1
    violations: list[dict[str, object]] = json.loads(out.stdout)["violations"]
    for v in violations:
        assert f"VIOLATION {v['term']}: {v['message']}" in text.stdout
    return violations


def fixed(tmp_path: Path, fixes: dict[str, float], **changes: float) -> None:
    """Applying any one of the named fixes alone passes the analysis."""
    team = load_team(greedy(tmp_path, **changes))
    for name, value in fixes.items():
        section, field = name.split(".")
        cfg = team.config
        part = dataclasses.replace(getattr(cfg, section), **{field: value * (1 - 1e-9)})
        result = analyze(dataclasses.replace(team, config=dataclasses.replace(
            cfg, **{section: part})))
        assert result.ok, (name, result.violations)


@pytest.mark.parametrize("changes, term", [
    ({"c2": 0.9}, "guidance.c2"),
    ({"c1": 1.2}, "guidance.c1"),
    ({"max_rotation_disagreement": 1.0}, "guidance.max_rotation_disagreement"),
    ({"c1": 0.8}, "guidance.c1 or guidance.c2"),  # was named 'guidance.c2': the largest term
])
def test_cli_gain_violation_names_the_gains_that_restore_it(
        tmp_path: Path, changes: dict[str, float], term: str) -> None:
    [v] = violated(greedy(tmp_path, **changes))
    assert v["term"] == term
    assert str(v["message"]).startswith("gain condition (eq. max) violated: c1_speed ")
    assert set(v["fixes"]) == set(term.split(" or "))  # type: ignore[arg-type]
    fixed(tmp_path, v["fixes"], **changes)  # type: ignore[arg-type]


def test_cli_gain_violation_no_gain_alone_names_all_three(tmp_path: Path) -> None:
    [v] = violated(greedy(tmp_path, c1=0.6, c2=0.7, max_rotation_disagreement=0.5))
    assert v["term"] == ("guidance.c1 and guidance.c2 and "
                         "guidance.max_rotation_disagreement")
    assert "no gain alone can restore it" in str(v["message"]) and v["fixes"] == {}


@pytest.mark.parametrize("changes, term, words", [
    ({"accel_norm": 2.5}, "limits.accel_norm", "set it to at most 2.203"),
    ({"accel_axis": 1.6, "accel_norm": 2.2}, "limits.accel_axis", "set it to at most 1.558"),
    ({"bank_deg": 40.0}, "limits.bank_deg", "set it below 35.19"),
])
def test_cli_limit_violation_names_the_limit(tmp_path: Path, changes: dict[str, float],
                                             term: str, words: str) -> None:
    [v] = violated(greedy(tmp_path, **changes))
    assert v["term"] == term and words in str(v["message"])
    fixed(tmp_path, v["fixes"], **changes)  # type: ignore[arg-type]


def test_cli_bad_config_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text("name: x\n")
    out = run_gcs("analyze", str(path))
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1
    assert "bad.yaml: airframe: missing required field" in out.stderr


def test_a_team_is_analysed_once_and_a_changed_team_afresh() -> None:
    """The command line, the scenario check and the GCS each ask for the analysis of the
    same loaded team: it is computed once; a team made with other settings has its own."""
    team = load_team(SQUARE)
    first = analyze(team)
    assert analyze(team) is first
    heavier = dataclasses.replace(team, config=dataclasses.replace(
        team.config, payload=dataclasses.replace(team.config.payload, mass=0.6)))
    assert analyze(heavier) is not first
    assert analyze(heavier).equilibrium_tension > first.equilibrium_tension


def test_a_team_loaded_again_is_not_analysed_again_and_a_changed_one_is() -> None:
    """The analysis is a function of the config: the same file loaded twice (a suite's
    worker, flights of many seeds) gives the same analysis object; another payload another."""
    first = analyze(load_team(SQUARE))
    assert analyze(load_team(SQUARE)) is first
    team = load_team(SQUARE)
    heavier = dataclasses.replace(team, config=dataclasses.replace(
        team.config, payload=dataclasses.replace(team.config.payload, mass=0.5)))
    other = analyze(heavier)
    assert other is not first and other.vertical_load > first.vertical_load
