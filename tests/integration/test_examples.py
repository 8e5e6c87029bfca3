"""Every script of ``examples/`` runs from the repository root and prints real figures.

Each example is run as a user runs it (``python examples/NN_name.py`` in a
subprocess, with a deadline); example 02 flies the short scenario once (about
10-40 s) and example 03 reads the log it recorded, whose figures must agree.
"""

from __future__ import annotations

import ast
import importlib.util
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from gcs.analysis import analyze
from gcs.common import shipped_config
from gcs.config import load_team
from tests.support.paths import ROOT

EXAMPLES = ROOT / "examples"
#: The examples this file runs; a new one must get its test here.
RUN_HERE = ("01_analyse_a_team.py", "02_fly_headless.py", "03_read_a_log.py")


def run_example(name: str, *args: str, timeout: float) -> subprocess.CompletedProcess[str]:
    """``python examples/NAME ARGS`` from the repository root, output captured."""
    return subprocess.run([sys.executable, str(EXAMPLES / name), *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout, check=False)


def figures(stdout: str) -> dict[str, list[str]]:
    """The ``key  value`` lines of examples 02 and 03: every value of each key, in order."""
    out: dict[str, list[str]] = {}
    for line in stdout.splitlines():
        key, _, value = line.partition(" ")
        out.setdefault(key, []).append(value.strip())
    return out


def number(pattern: str, text: str) -> float:
    """The number the regex ``pattern`` captures in ``text`` (fails the test if absent)."""
    found = re.search(pattern, text, re.MULTILINE)
    assert found is not None, f"{pattern!r} not in:\n{text}"
    return float(found.group(1))


@pytest.mark.parametrize("name", RUN_HERE)
def test_an_example_is_a_documented_script_with_a_main(name: str) -> None:
    tree = ast.parse((EXAMPLES / name).read_text("utf-8"))
    doc = ast.get_docstring(tree)
    assert doc and f"python examples/{name}" in doc, f"{name}: docstring says how to run it"
    mains = [n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "main"]
    assert mains and mains[0].args.args[0].arg == "argv", f"{name}: def main(argv)"
    guard = [n for n in tree.body if isinstance(n, ast.If)
             and "__main__" in ast.unparse(n.test)]
    assert guard and "raise SystemExit(main())" in ast.unparse(guard[0]), name
    assert f"`{name}`" in (EXAMPLES / "README.md").read_text("utf-8"), f"README lacks {name}"


def test_every_example_is_run_by_this_file() -> None:
    assert sorted(p.name for p in EXAMPLES.glob("*.py")) == sorted(RUN_HERE)


def test_01_prints_the_squares_analysis_and_a_zero_command_at_rest() -> None:
    out = run_example("01_analyse_a_team.py", timeout=180)
    assert out.returncode == 0, out.stdout + out.stderr
    text = out.stdout
    # docs/analysis.md: the paper's square
    assert number(r"^vertical load per vehicle\s+([\d.]+) N$", text) == 5.230
    assert number(r"^max tilt\s+([\d.]+) rad", text) == 0.614
    assert number(r"^horizontal force at bank limit\s+([\d.]+) N$", text) == 2.189
    assert number(r"^max guidance acceleration\s+([\d.]+) m/s\^2$", text) == 2.203
    assert number(r"^  per axis\s+([\d.]+) m/s\^2$", text) == 1.558
    assert number(r"^gain condition \(eq. max\)\s+([\d.]+) <= [\d.]+ m/s\^2$", text) == 1.509
    assert re.search(r"^ok\s+True$", text, re.MULTILINE), text
    assert number(r"^command at rest, in shape\s+(\S+) m/s\^2", text) < 1e-9
    assert number(r"^command at rest, full forward\s+(\S+) m/s\^2", text) > 0.1


def test_01_main_called_in_process_prints_what_analyze_gives(
        capsys: pytest.CaptureFixture[str]) -> None:
    path = EXAMPLES / "01_analyse_a_team.py"
    spec = importlib.util.spec_from_file_location("example_01", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    config = shipped_config("bebop_triangle.yaml")
    assert module.main(["--config", str(config)]) == 0
    text = capsys.readouterr().out
    a = analyze(load_team(config))
    assert number(r"^vertical load per vehicle\s+([\d.]+) N$", text) == round(a.vertical_load, 3)
    assert number(r"^  per axis\s+([\d.]+) m/s\^2$", text) == round(a.max_accel_axis, 3)
    assert f"team {a.team}: {a.vehicles} vehicles" in text


@pytest.fixture(scope="module")
def flight(tmp_path_factory: pytest.TempPathFactory) -> tuple[subprocess.CompletedProcess[str],
                                                             Path]:
    """Example 02 run once on the short scenario at full speed, and the log it kept."""
    log = tmp_path_factory.mktemp("example02") / "flight.tlog"
    out = run_example("02_fly_headless.py", "--record", str(log), "--speed", "max", timeout=300)
    return out, log


def test_02_flies_the_short_scenario_in_shape(
        flight: tuple[subprocess.CompletedProcess[str], Path]) -> None:
    out, log = flight
    assert out.returncode == 0, out.stdout + out.stderr
    f = figures(out.stdout)
    assert f["completed"] == ["True"] and f["error"] == ["None"], out.stdout
    assert 0.0 < float(f["worst_distance_error_m"][0]) < 0.3, out.stdout
    assert float(f["payload_lift_m"][0]) > 0.5, out.stdout  # the 1 m lift of the scenario
    assert float(f["duration_s"][0]) > 30.0 and int(f["ticks"][0]) > 120, out.stdout
    phases = ast.literal_eval(f["phases"][0])
    assert "formation" in phases and phases[-1] == "landed", phases
    assert f["record"][0].startswith(f"{log} "), out.stdout
    assert log.stat().st_size > 100_000


def test_03_reads_the_log_of_02_and_agrees_with_it(
        flight: tuple[subprocess.CompletedProcess[str], Path], tmp_path: Path) -> None:
    flown, log = flight
    assert log.is_file(), f"example 02 wrote no log:\n{flown.stdout}{flown.stderr}"
    out = run_example("03_read_a_log.py", str(log), "--out", str(tmp_path / "report"),
                      timeout=180)
    assert out.returncode == 0, out.stdout + out.stderr
    read, live = figures(out.stdout), figures(flown.stdout)
    assert read["vehicles"] == ["[1, 2, 3, 4]"], out.stdout
    for key in ("duration_s", "ticks", "worst_distance_error_m", "payload_lift_m",
                "worst_bank_rad", "worst_accel_cmd_m_s2"):
        assert read[key] == live[key], f"{key}: log {read[key]}, flight {live[key]}"
    changes = [re.fullmatch(r"\s*([\d.]+) s  (.+)", v) for v in read["phase"]]
    assert all(changes), read["phase"]
    assert [m.group(2) for m in changes if m] == ast.literal_eval(live["phases"][0])
    assert read["damage"] == ["None"], out.stdout
    summary = json.loads((tmp_path / "report" / "summary.json").read_text())
    assert summary["metrics"]["worst_distance_error_m"] == float(
        live["worst_distance_error_m"][0])
    assert (tmp_path / "report" / "formation.png").stat().st_size > 0


def test_03_refuses_a_file_that_is_no_log_in_one_line() -> None:
    out = run_example("03_read_a_log.py", str(ROOT / "README.md"), timeout=120)
    assert out.returncode == 2, out.stdout + out.stderr
    assert out.stderr.count("\n") == 1 and "no MAVLink messages" in out.stderr, out.stderr
