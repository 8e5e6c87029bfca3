"""``gcs analyze --verify``: the team flown in the lockstep simulator, once per seed in
parallel processes, measured from the simulator's truth against the analysis.

Real parts: ``gcs analyze`` in a subprocess starts its flights in worker processes,
each a real ``python -m sim`` behind zenoh and a GCS recording a .tlog. The
comparison itself is a plain function, checked here with made-up numbers too.
"""

from __future__ import annotations

import json
import math
import re
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from gcs.analysis import accelerating_share, analyze, safe_guidance
from gcs.app import (
    FIGURES,
    FlightFigures,
    VerifyResult,
    compare,
    format_verify,
    load_scenario,
    parse_seeds,
    rope_loads,
)
from gcs.app._scenario import scenario_scales
from gcs.common import ConfigError
from gcs.config import load_team
from tests.support.commands import gcs_here, run_gcs
from tests.support.paths import SHORT, SQUARE

PAPER = "configs/scenarios/paper_flight.yaml"

_ROW = re.compile(r"^  (?P<label>.+?)\s{2,}(?P<predicted>[-\d.]+)( \S+)?\s+"
                  r"(?P<measured>[-\d.]+)( \S+)? \((?P<seed>\d+)\)\s+(?P<margin>[-+\d.]+)"
                  r"( \S+)?\s+(?P<verdict>OK|EXCEEDED)$")


def _rows(stdout: str) -> dict[str, dict[str, str]]:
    out = {}
    for line in stdout.splitlines():
        m = _ROW.match(line)
        if m:
            out[m["label"]] = m.groupdict()
    return out


def _team(tmp_path: Path, **changes: dict[str, float]) -> Path:
    """The paper's square with some sections changed, in ``tmp_path``."""
    raw = yaml.safe_load(Path(SQUARE).read_text())
    raw["airframe"] = str(Path("configs/airframes/bebop2.yaml").resolve())
    for section, values in changes.items():
        raw[section].update(values)
    path = tmp_path / "team.yaml"
    path.write_text(yaml.safe_dump(raw))
    return path


def test_the_square_is_flown_and_held_to_its_analysis() -> None:
    """The paper flight on seed 2, which came nearest the bounds of seeds 1-3 in tension,
    tilt, span and distance error (share: seed 3, 0.286 against 0.411): every figure
    within the certificate. Several seeds in parallel, and the worst of them taken, are
    test_fly_seeds' and the comparison's tests below."""
    out = run_gcs("analyze", SQUARE, "--verify", "--seeds", "2")
    assert out.returncode == 0, out.stdout + out.stderr
    rows = _rows(out.stdout)
    assert list(rows) == [f.label for f in FIGURES], out.stdout
    analysis = json.loads(gcs_here("analyze", SQUARE, "--json").stdout)
    load = analysis["static_load"]
    predicted = {label: float(r["predicted"]) for label, r in rows.items()}
    # the square: accelerating, at the scales the paper flight flies (0.9 to 1.1, held at
    # 1.077): 0.41, above the 0.386 at scale 1, below the 0.629 of the smallest scale flown
    team = load_team(SQUARE)
    flown = (0.9, 1.0, analysis["scales_flown"]["max"])
    assert scenario_scales(load_scenario(PAPER), safe_guidance(team, analyze(team))) == \
        pytest.approx(flown)
    accelerating = accelerating_share(team, team.config.limits.accel_norm, flown).share
    assert predicted[FIGURES[0].label] == pytest.approx(accelerating, abs=5e-4)
    assert accelerating_share(team, team.config.limits.accel_norm).share + 0.01 \
        < accelerating < load["accel_share"] - 0.1
    assert predicted[FIGURES[1].label] == pytest.approx(load["worst_share"], abs=5e-4)
    assert predicted["tilt <= bank limit"] == pytest.approx(analysis["bank_limit_rad"],
                                                             abs=5e-4)
    assert predicted["distance error <= safe deformation"] == pytest.approx(
        analysis["safe_deformation"]["margin_m"], abs=5e-4)
    for r in rows.values():  # each row's margin is its bound less the measured figure
        assert float(r["margin"]) == pytest.approx(
            float(r["predicted"]) - float(r["measured"]), abs=2e-3)
        assert r["verdict"] == ("OK" if float(r["margin"]) >= 0 else "EXCEEDED")
        assert r["seed"] == "2"
    # the payload was carried (the paper's square hangs a quarter of it on each rope, a
    # little more while it swings) and no vehicle came near the analysis' load bounds
    share = float(rows[FIGURES[0].label]["measured"])
    assert 0.25 <= share < 0.333
    for label in (FIGURES[0].label, FIGURES[1].label, FIGURES[3].label,
                  "tilt <= bank limit"):
        assert rows[label]["verdict"] == "OK", out.stdout
    assert all(r["verdict"] == "OK" for r in rows.values()), out.stdout
    assert "result: OK" in out.stdout
    assert "seed 2 completed" in out.stderr


def test_a_flight_beyond_a_tiny_safe_deformation_fails_naming_the_figure(
        tmp_path: Path) -> None:
    """A square whose acceleration limit leaves it 2 cm of safe deformation passes the
    analysis (assuming a push its weakest mode holds within that: 0.005 m/s^2 gives
    0.013 m), and its flight, pulled 0.2 m in at lift-off, exceeds it."""
    team = _team(tmp_path, limits={"accel_norm": 2.729},
                 analysis={"design_rope_angle_deg": 40.0, "disturbance_accel": 0.005})
    assert gcs_here("analyze", str(team)).returncode == 0
    out = run_gcs("analyze", str(team), "--verify", "--scenario", SHORT, "--seeds", "3",
                  "--jobs", "1")
    assert out.returncode == 1, out.stdout + out.stderr
    row = _rows(out.stdout)["distance error <= safe deformation"]
    assert float(row["predicted"]) == pytest.approx(0.023, abs=1e-3)
    assert row["verdict"] == "EXCEEDED" and row["seed"] == "3"
    assert re.search(r"^EXCEEDED error_safe: measured 0\.\d+ \(seed 3\) > predicted 0\.023$",
                     out.stdout, re.M), out.stdout
    assert "result: FAILED" in out.stdout


def test_a_team_the_analysis_refuses_is_not_flown(tmp_path: Path) -> None:
    team = _team(tmp_path, payload={"mass": 2.0})
    start = time.monotonic()
    out = gcs_here("analyze", str(team), "--verify", "--json")
    assert out.returncode == 1
    assert time.monotonic() - start < 20.0
    assert json.loads(out.stdout)["violations"]  # the analysis, as without --verify
    assert "flying" not in out.stderr


@pytest.mark.parametrize("args", [("--seeds", "4-1"), ("--seeds", "x"), ("--jobs", "0"),
                                  ("--gusts", "-0.5"), ("--gusts", "nan")])
def test_bad_verify_options_are_one_line(args: tuple[str, str]) -> None:
    out = gcs_here("analyze", SQUARE, "--verify", *args)
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1 and args[0] in out.stderr


def test_seeds_are_ranges_and_lists() -> None:
    assert parse_seeds("1-4") == (1, 2, 3, 4)
    assert parse_seeds("7") == (7,)
    assert parse_seeds("1,3,9-10,3") == (1, 3, 9, 10)
    with pytest.raises(ConfigError, match="--seeds"):
        parse_seeds("-1")


def _flight(seed: int, **values: float | None) -> FlightFigures:
    return FlightFigures(seed=seed, completed=True, error=None, wall_s=1.0, **values)


_MEASURED = {"share": 0.29, "tension": 1.45, "pull": 0.95, "tilt": 0.19, "span": 1.55,
             "distance_error": 0.12}


def _predicted(**changes: float) -> dict[str, float]:
    return {"share_design": 1 / 3, "share_worst": 0.52, "tension_design": 1.69,
            "tension_worst": 2.59, "pull_safe": 1.32, "tilt_bank": 0.349, "span_safe": 1.587,
            "error_safe": 0.173, "error_eq_max": 1.0, **changes}


def test_the_comparison_takes_the_worst_seed_and_flags_what_exceeds() -> None:
    flights = [_flight(1, **_MEASURED), _flight(2, **(_MEASURED | {"distance_error": 0.15}))]
    rows = {r.figure.key: r for r in compare(_predicted(error_safe=0.05), flights)}
    assert [r.figure.key for r in rows.values() if not r.ok] == ["error_safe"]
    bad = rows["error_safe"]
    assert (bad.measured, bad.seed) == (0.15, 2) and bad.margin == pytest.approx(-0.1)
    assert rows["error_eq_max"].ok and rows["error_eq_max"].margin == pytest.approx(0.85)
    result = VerifyResult("square", "short_flight", (1, 2), 2, 10.0, tuple(flights),
                          tuple(rows.values()))
    assert not result.ok and result.to_json()["exceeded"] == ["error_safe"]
    text = format_verify(result)
    assert "EXCEEDED error_safe: measured 0.150 (seed 2) > predicted 0.050" in text
    assert text.endswith("result: FAILED (1 figure(s) exceeded, 0 flight(s) incomplete)")
    ok = VerifyResult("square", "short_flight", (1, 2), 2, 10.0, tuple(flights),
                      tuple(compare(_predicted(), flights)))
    assert ok.ok and format_verify(ok).endswith("result: OK (2 flights within the analysis)")


def test_an_incomplete_flight_or_an_unmeasured_figure_fails() -> None:
    lost = FlightFigures(seed=5, completed=False, error="ScenarioError: timed out",
                         wall_s=3.0, **_MEASURED)
    result = VerifyResult("square", "s", (5,), 1, 3.0, (lost,),
                          tuple(compare(_predicted(), [lost])))
    assert not result.exceeded and not result.ok
    assert "FLIGHT seed 5 did not complete: ScenarioError: timed out" in format_verify(result)
    grounded = _flight(1, **(_MEASURED | {"share": None}))  # the payload never rose
    row = compare(_predicted(), [grounded])[0]
    assert row.measured is None and not row.ok


def test_rope_loads_split_a_pull_into_its_vertical_and_horizontal_parts() -> None:
    payload = np.array([[1.0, 0.0, 1.0]])
    vehicles = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]])
    vertical, horizontal, reach = rope_loads(payload, vehicles, np.array([[math.sqrt(2), 2.0]]))
    np.testing.assert_allclose(vertical, [[1.0, 2.0]])
    np.testing.assert_allclose(horizontal, [[1.0, 0.0]], atol=1e-12)
    np.testing.assert_allclose(reach, [[1.0, 0.0]])


def test_a_team_beyond_the_checked_sizes_is_refused_and_certified_by_its_flights(
        tmp_path: Path) -> None:
    """A ring of twelve, tied across and carrying the 0.13 kg its worst share allows,
    passes every condition but its size: the analysis alone refuses it, and --verify flies
    it anyway, its flights being the certificate. They refute it: the ring comes 1.03 m
    out of its shape against 0.785 m safe on the short flight (2.1 m on the paper's)."""
    raw = yaml.safe_load(Path("tests/data/bebop_ring12_tied.yaml").read_text())
    raw["airframe"] = str(Path("configs/airframes/bebop2.yaml").resolve())
    raw["payload"]["mass"] = 0.13
    team = tmp_path / "ring.yaml"
    team.write_text(yaml.safe_dump(raw))
    alone = analyze(load_team(team))
    assert [v.term for v in alone.violations] == ["vehicles"] and alone.unchecked_only
    out = run_gcs("analyze", str(team), "--verify", "--scenario", SHORT, "--seeds", "1",
                  "--jobs", "1")
    assert "a team of 12 is beyond the 6 vehicles" in out.stderr
    assert "seed 1 completed" in out.stderr, out.stderr
    assert out.returncode == 1, out.stdout
    row = _rows(out.stdout)["distance error <= safe deformation"]
    assert row["verdict"] == "EXCEEDED" and float(row["measured"]) > 0.9, out.stdout
    assert "certificate" not in out.stdout


def test_flights_within_the_analysis_certify_a_team_beyond_the_checked_sizes(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """What `gcs analyze --verify` says when a team refused only for its size flies within
    every figure (the flights replaced by one that exceeded nothing):
    exit 0, the certificate line, and the refusal in the JSON."""
    import argparse

    from gcs import cli

    raw = yaml.safe_load(Path("tests/data/bebop_ring12_tied.yaml").read_text())
    raw["airframe"] = str(Path("configs/airframes/bebop2.yaml").resolve())
    raw["payload"]["mass"] = 0.13
    (tmp_path / "ring.yaml").write_text(yaml.safe_dump(raw))
    team = load_team(tmp_path / "ring.yaml")
    analysis = analyze(team)
    assert analysis.unchecked_only
    flight = FlightFigures(seed=1, completed=True, error=None, wall_s=1.0)

    def flown(team_: object, scenario: object, analysis_: object, **_: object) -> VerifyResult:
        return VerifyResult(team=team.config.name, scenario="short_flight", seeds=(1,),
                            jobs=1, wall_s=1.0, flights=(flight,), rows=())

    monkeypatch.setattr("gcs.app.verify", flown)
    args = argparse.Namespace(scenario=SHORT, seeds="1", jobs="1", gusts=None, json=False)
    assert cli._verify(args, team, analysis) == 0
    out = capsys.readouterr().out
    assert "result: OK" in out
    assert "these flights are the certificate of this team of 12" in out
    assert "with --override-analysis" in out
    args.json = True
    assert cli._verify(args, team, analysis) == 0
    assert json.loads(capsys.readouterr().out)["analysis_refuses"] == ["vehicles"]
