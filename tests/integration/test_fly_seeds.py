"""``gcs fly --seeds``: one lockstep flight per simulator seed, several at a time, and the
spread of each figure over them (``gcs.testing.fly_seeds`` from Python).

Real parts: ``gcs fly`` in a subprocess starts its flights in worker processes, each a
real ``python -m sim`` behind zenoh and a GCS in lockstep with it, on the short
scenario. The spread itself is a plain function, checked on those flights' figures.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gcs.app import fly_seeds_in_parallel, parse_jobs
from gcs.common import ConfigError
from gcs.config import load_team
from gcs.testing import Metrics, SeedRun, fly_seeds, spread
from tests.support.commands import run_gcs
from tests.support.paths import SHORT, SQUARE

#: Sticks before the lift: the flight fails at its second step, a few seconds in.
_FAILING = """name: sticks_on_the_ground
steps:
  - {action: arm}
  - {sticks: {forward: 0.5}, duration: 1}
"""
_WHY = "sticks move the team in formation flight only"


def _numbers(flight: dict) -> dict[str, float]:
    """A flight's numeric figures, by-phase ones as ``name.phase`` (as the summary has them)."""
    out: dict[str, float] = {}
    for key, value in flight.items():
        if isinstance(value, dict):
            out |= {f"{key}.{phase}": v for phase, v in value.items() if v is not None}
        elif isinstance(value, int | float) and not isinstance(value, bool) and key not in (
                "seed", "wall_s"):
            out[key] = value
    return out


def test_three_seeds_two_at_a_time_give_three_flights_and_the_spread_of_each_figure() -> None:
    out = run_gcs("fly", "--config", SQUARE, "--scenario", SHORT, "--seeds", "1-3",
                  "--jobs", "2", "--json")
    assert out.returncode == 0, out.stdout + out.stderr
    data = json.loads(out.stdout)
    assert (data["seeds"], data["jobs"], data["completed"], data["ok"]) == ([1, 2, 3], 2, 3, True)
    flights = data["flights"]
    assert [f["seed"] for f in flights] == [1, 2, 3]
    assert all(f["completed"] and f["phases"][-1] == "landed" for f in flights)
    figures = [_numbers(f) for f in flights]
    summary = data["summary"]
    assert set(summary) == set().union(*figures)
    for name, s in summary.items():
        values = [f[name] for f in figures if name in f]
        assert s["n"] == len(values)
        assert s["max"] == pytest.approx(max(values), abs=1e-9), name
        assert s["min"] == pytest.approx(min(values), abs=1e-9), name
        assert s["min"] <= s["median"] <= s["p90"] <= s["max"], name
        assert s["mean"] == pytest.approx(sum(values) / len(values), abs=1e-4), name
    worst = summary["worst_distance_error_m"]
    assert figures[worst["worst_seed"] - 1]["worst_distance_error_m"] == worst["max"]
    lift = summary["payload_lift_m"]  # less lift is worse
    assert figures[lift["worst_seed"] - 1]["payload_lift_m"] == lift["min"]
    # each seed its own noise and gusts: three draws, not one flight thrice
    assert len({f["worst_distance_error_m"] for f in figures}) > 1
    done = [line for line in out.stderr.splitlines() if " completed (" in line]
    assert sorted(line.split()[3] for line in done) == ["1", "2", "3"], out.stderr
    assert "2 at a time" in out.stderr


def test_one_seed_alone_is_the_flight_gcs_fly_gives_for_it(
        short_flight: tuple[dict, Path]) -> None:
    """``--seeds 0`` summarises the one flight of ``gcs fly`` (seed 0): every statistic is
    its figure, and that flight is the one a plain ``gcs fly`` flies (the session's short
    flight), to the last digit (lockstep, actions and scenario at ticks: only the
    wall-time figures differ; the same beside a CPU hog is test_simteam's)."""
    out = run_gcs("fly", "--config", SQUARE, "--scenario", SHORT, "--json", "--quiet",
                  "--seeds", "0")
    assert out.returncode == 0, out.stdout + out.stderr
    assert out.stderr == ""  # --quiet: not even a line per flight
    data, (alone, _) = json.loads(out.stdout), short_flight
    (flight,) = data["flights"]
    figures = _numbers(flight)
    for name, s in data["summary"].items():
        assert s["n"] == 1 and s["worst_seed"] == 0
        assert s["min"] == s["median"] == s["p90"] == s["max"] == s["mean"] == figures[name]
    drop = {*Metrics.WALL, "seed", "wall_s", "record"}  # the short flight was recorded
    assert {k: v for k, v in flight.items() if k not in drop} == \
        {k: v for k, v in alone.items() if k not in drop}
    assert set(data["summary"]) == set(_numbers(alone))


def test_a_flight_that_fails_is_listed_with_its_reason(tmp_path: Path) -> None:
    scenario = tmp_path / "fails.yaml"
    scenario.write_text(_FAILING)
    out = run_gcs("fly", "--config", SQUARE, "--scenario", str(scenario), "--seeds", "5,7",
                  "--jobs", "2")
    assert out.returncode == 1, out.stdout + out.stderr
    lines = out.stdout.splitlines()
    assert "0 of 2 completed" in lines[0]
    for seed in (5, 7):
        assert any(line.startswith(f"FLIGHT seed {seed} did not complete: step 2 ") and _WHY
                   in line for line in lines), out.stdout
        assert f"seed {seed} did NOT complete: step 2" in out.stderr


def test_from_python_a_failed_flight_keeps_its_figures_and_its_reason(tmp_path: Path) -> None:
    scenario = tmp_path / "fails.yaml"
    scenario.write_text(_FAILING)
    runs = fly_seeds(SQUARE, scenario, "3", jobs=1)
    assert not runs.ok and runs.seeds == (3,) and runs.summary == {}
    (lost,) = runs.failed
    assert lost.seed == 3 and _WHY in (lost.error or "")
    assert lost.metrics is not None and lost.metrics.phases[-1] == "armed"


def _flown_unless_two(seed: int) -> str:
    """A worker's work: seed 2's raises, as a flight whose simulator never came up."""
    if seed == 2:
        raise RuntimeError("the simulator did not come up")
    return "flown"


def test_a_worker_that_raises_loses_no_seed() -> None:
    lines: list[str] = []
    results = fly_seeds_in_parallel(
        load_team(SQUARE), _flown_unless_two, [3, 2, 1], jobs=2,
        lost=lambda seed, why: f"lost {seed}: {why}", say=lines.append,
        error_of=lambda r: None if r == "flown" else r)
    assert results == ["flown", "lost 2: RuntimeError: the simulator did not come up", "flown"]
    assert sum("completed (" in line for line in lines) == 2
    assert any(line.startswith("seed 2 did NOT complete: lost 2") for line in lines)


def test_the_spread_is_of_the_completed_flights() -> None:
    def run(seed: int, error: float, *, failed: bool = False) -> SeedRun:
        figures = {f: 0 for f in Metrics.__dataclass_fields__} | {
            "phases": ["landed"], "worst_distance_error_by_phase_m": {"hover": error},
            "worst_distance_error_m": error, "payload_lift_m": 1.0 - error,
            "worst_swing_rad": None, "real_time_factor": None}
        return SeedRun(seed, Metrics.from_json(figures), "lost" if failed else None, 1.0)

    runs = [run(1, 0.1), run(2, 0.3), run(3, 0.2), run(4, 9.0, failed=True)]
    s = spread(runs)
    assert "worst_swing_rad" not in s  # not measured: not summarised
    e = s["worst_distance_error_m"]
    assert (e.n, e.min, e.median, e.max, e.worst_seed) == (3, 0.1, 0.2, 0.3, 2)
    assert e.p90 == pytest.approx(0.28) and e.mean == pytest.approx(0.2)
    assert s["worst_distance_error_by_phase_m.hover"].max == 0.3
    assert s["payload_lift_m"].worst_seed == 2  # the least lift


@pytest.mark.parametrize(("args", "bad"), [
    (("--seeds", "4-1"), "--seeds"), (("--seeds", "1-3", "--jobs", "two"), "--jobs"),
    (("--jobs", "2"), "--jobs"), (("--seeds", "1", "--connect", "tcp/127.0.0.1:7447"), "--seeds"),
    (("--gusts", "-1"), "--gusts"), (("--seeds", "1", "--gusts", "strong"), "--gusts"),
    (("--gusts", "0.5", "--connect", "tcp/127.0.0.1:7447"), "--gusts")])
def test_bad_seeds_jobs_or_gusts_are_one_line_naming_the_option(args: tuple[str, ...],
                                                                bad: str) -> None:
    out = run_gcs("fly", "--config", SQUARE, "--scenario", SHORT, *args)
    assert out.returncode == 2, out.stdout + out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and f"error: {bad}: " in out.stderr, \
        out.stderr
    assert out.stdout == ""


def test_jobs_are_a_whole_number_from_one() -> None:
    assert (parse_jobs(None), parse_jobs("3"), parse_jobs(2)) == (None, 3, 2)
    for bad in ("0", "-1", "1.5", ""):
        with pytest.raises(ConfigError, match="--jobs"):
            parse_jobs(bad)
