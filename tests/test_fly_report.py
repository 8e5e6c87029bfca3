"""A shortened flight end to end (sim process + zenoh + MAVLink + GCS), then its report.

Real parts only: `gcs fly` starts `python -m sim` as its own process, the GCS
reaches the vehicles over zenoh on loopback with MAVLink 2, the recorder writes
a .tlog, and `gcs report` reads it back.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest

from gcs import report
from gcs.flightlog import FlightLog
from gcs.logreader import TlogIndex
from tests.conftest import SHORT, SQUARE, run_gcs


def test_short_flight_lifts_the_payload_and_keeps_the_shape(
        short_flight: tuple[dict, Path]) -> None:
    m, _ = short_flight
    assert m["completed"] and m["error"] is None
    assert m["phases"][-1] == "landed"
    assert {"lifting", "formation", "setting down"} <= set(m["phases"])
    assert m["payload_lift_m"] > 0.8  # lift height 1 m above the taut-rope altitude
    assert m["worst_distance_error_m"] <= 0.30  # the paper's flight figure
    assert m["worst_swing_rad"] < 0.2
    assert 0.0 < m["worst_bank_rad"] < 0.36  # below the 20 degree bank limit (+ noise)
    assert 0.5 < m["rope_tension_min_N"] < m["rope_tension_max_N"] < 3.0
    assert m["real_time_factor"] > 1.0  # faster than real time


def test_the_same_flight_on_every_run_whatever_the_load(
        short_flight: tuple[dict, Path]) -> None:
    """Lockstep with actions and scenario at ticks: a second run, with a CPU hog beside
    it, flies the same flight to the last digit; only the wall-time figure differs."""
    first, _ = short_flight
    hog = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        out = run_gcs("fly", "--config", SQUARE, "--scenario", SHORT, "--json")
    finally:
        hog.kill()
        hog.wait()
    assert out.returncode == 0, out.stderr
    second = json.loads(out.stdout)
    wall = {"real_time_factor", "record"}
    assert {k: v for k, v in second.items() if k not in wall} == \
        {k: v for k, v in first.items() if k not in wall}


def test_missing_scenario_is_one_line() -> None:
    out = run_gcs("fly", "--config", SQUARE, "--scenario", "configs/scenarios/missing.yaml")
    assert out.returncode == 2
    assert "missing.yaml: cannot read file" in out.stderr


def test_report_matches_the_flight(short_flight: tuple[dict, Path], tmp_path: Path) -> None:
    m, log = short_flight
    out = run_gcs("report", str(log), "--out", str(tmp_path), "--json", "--quiet")
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)
    for name in ("formation.png", "trajectories.png", "distance_errors.png",
                 "accelerations.png", "summary.json", "summary.md"):
        assert (tmp_path / name).stat().st_size > 1000 or name.endswith((".json", ".md"))
    r = summary["metrics"]
    for key in ("worst_distance_error_m", "payload_lift_m", "worst_swing_rad",
                "worst_bank_rad", "worst_accel_cmd_m_s2", "rope_tension_max_N"):
        assert r[key] == pytest.approx(m[key], abs=2e-3), key
    assert r["duration_s"] == pytest.approx(m["duration_s"], abs=0.01)
    assert r["phases"] == m["phases"]
    for phase, value in m["worst_distance_error_by_phase_m"].items():
        assert r["worst_distance_error_by_phase_m"][phase] == pytest.approx(value, abs=2e-3)
    assert summary["missing"] == []
    assert summary["vehicles"] == [1, 2, 3, 4]
    # what the vehicles sent, per system/component; the GCS's own senders are left out
    assert summary["link_losses"] == {"1/1": 0, "2/1": 0, "3/1": 0, "4/1": 0}


def test_truncated_log_still_reports(short_flight: tuple[dict, Path], tmp_path: Path) -> None:
    _, log = short_flight
    cut = tmp_path / "cut.tlog"
    data = log.read_bytes()
    index = TlogIndex.build(log)
    middle = len(index) // 2  # cut inside a frame: a cut on a record boundary is a whole log
    cut.write_bytes(data[: int(index.offset[middle]) + int(index.length[middle]) // 2])
    out = run_gcs("report", str(cut), "--out", str(tmp_path / "r"), "--quiet")
    assert out.returncode == 0, out.stderr
    assert "truncated=True" in out.stdout
    parsed = FlightLog.load(cut)
    assert parsed.index.truncated and len(parsed.tick_t) > 10


def test_corrupt_log_still_reports_and_says_what_was_skipped(
        short_flight: tuple[dict, Path], tmp_path: Path) -> None:
    m, log = short_flight
    data = bytearray(log.read_bytes())
    rng = np.random.default_rng(2)
    for k in rng.choice(len(data), 2000, replace=False):  # about one byte in 600
        data[k] ^= int(rng.integers(1, 256))
    bad = tmp_path / "corrupt.tlog"
    bad.write_bytes(bytes(data))
    out = run_gcs("report", str(bad), "--out", str(tmp_path / "r"), "--json", "--quiet")
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)
    r = summary["metrics"]
    assert r["duration_s"] == pytest.approx(m["duration_s"], abs=1.0)
    assert summary["vehicles"] == [1, 2, 3, 4]  # no systems made of damaged bytes
    assert set(summary["link_losses"]) == {"1/1", "2/1", "3/1", "4/1"}
    times = [p["t_s"] for p in summary["phases"]]
    assert times == sorted(times) and times[-1] < m["duration_s"] + 1.0
    assert set(r["phases"]) <= set(m["phases"])
    assert summary["corrupt_bytes_skipped"] > 1000 and summary["bad_timestamps_rejected"] > 0
    assert 0.8 * 22_000 < summary["messages"] < len(TlogIndex.build(log))
    for name in ("formation.png", "trajectories.png", "accelerations.png"):
        assert (tmp_path / "r" / name).stat().st_size > 1000
    text = run_gcs("report", str(bad), "--out", str(tmp_path / "r2"), "--quiet").stdout
    assert "corrupt bytes skipped=" in text and "damaged timestamp rejected=" in text


def test_acceleration_limits_are_drawn_against_their_own_quantity(
        short_flight: tuple[dict, Path]) -> None:
    log = FlightLog.load(short_flight[1])
    fig = report._accelerations(log)
    assert fig is not None and log.team is not None
    norm_ax, axis_ax = fig.axes

    def levels(ax: plt.Axes) -> set[float]:  # horizontal lines: y constant over the line
        return {round(float(y[0]), 6) for line in ax.get_lines()
                if len(y := np.asarray(line.get_ydata(), dtype=float)) == 2 and y[0] == y[1]}

    norm, per_axis = float(log.team["accel_norm"]), float(log.team["accel_axis"])
    assert levels(norm_ax) == {round(norm, 6)}
    assert levels(axis_ax) == {round(per_axis, 6), round(-per_axis, 6)}
    plt.close(fig)


def test_unreadable_files_are_refused_in_one_line(tmp_path: Path) -> None:
    for command in ("report", "replay"):
        out = run_gcs(command, str(tmp_path))  # a folder, not a log
        assert out.returncode == 2, out.stderr
        assert out.stderr.count("\n") == 1 and str(tmp_path) in out.stderr
        assert "Traceback" not in out.stderr


def test_empty_and_garbage_logs_are_refused_in_one_line(tmp_path: Path) -> None:
    empty = tmp_path / "empty.tlog"
    empty.write_bytes(b"")
    out = run_gcs("report", str(empty), "--quiet")
    assert out.returncode == 2 and "empty file" in out.stderr
    junk = tmp_path / "junk.tlog"
    junk.write_bytes(bytes(range(256)) * 40)
    out = run_gcs("report", str(junk), "--quiet")
    assert out.returncode == 2 and "no MAVLink messages" in out.stderr
