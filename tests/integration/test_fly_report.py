"""A shortened flight end to end (sim process + zenoh + MAVLink + GCS), then its report.

Real parts only: `gcs fly` starts `python -m sim` as its own process, the GCS
reaches the vehicles over zenoh on loopback with MAVLink 2, the recorder writes
a .tlog, and `gcs report` reads it back.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest

from gcs.flightlog import FlightLog, TlogIndex
from gcs.flightlog import _report as report
from gcs.flightlog._figstyle import FORMATS
from gcs.flightlog._report import FIGURES
from gcs.wire import SAFETY_ARMED
from tests.support.commands import gcs_here, run_gcs
from tests.support.logfiles import VEHICLES, plain_copy, raw_messages
from tests.support.paths import SQUARE


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


def test_missing_scenario_is_one_line() -> None:
    out = run_gcs("fly", "--config", SQUARE, "--scenario", "configs/scenarios/missing.yaml")
    assert out.returncode == 2
    assert "missing.yaml: cannot read file" in out.stderr


def test_report_matches_the_flight(short_flight: tuple[dict, Path], tmp_path: Path) -> None:
    m, log = short_flight
    out = gcs_here("report", str(log), "--out", str(tmp_path), "--json", "--quiet")
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)
    assert summary["figures"] == _files(FIGURES)
    _figures_drawn(tmp_path, FIGURES)
    r = summary["metrics"]
    for key in ("worst_distance_error_m", "payload_lift_m", "worst_swing_rad",
                "worst_bank_rad", "worst_accel_cmd_m_s2", "rope_tension_min_N",
                "rope_tension_max_N"):
        assert r[key] == pytest.approx(m[key], abs=2e-3), key
    assert r["duration_s"] == pytest.approx(m["duration_s"], abs=0.01)
    assert r["ticks"] == m["ticks"]
    assert r["phases"] == m["phases"]
    assert summary["damage"] is None
    for phase, value in m["worst_distance_error_by_phase_m"].items():
        assert r["worst_distance_error_by_phase_m"][phase] == pytest.approx(value, abs=2e-3)
    assert summary["missing"] == []
    assert summary["vehicles"] == [1, 2, 3, 4]
    # what the vehicles sent, per system/component; the GCS's own senders are left out
    assert summary["link_losses"] == {"1/1": 0, "2/1": 0, "3/1": 0, "4/1": 0}


def test_a_whole_flight_is_not_cut_short(short_flight: tuple[dict, Path]) -> None:
    _, log = short_flight
    assert FlightLog.load(log).cut_short() is None


def test_truncated_log_still_reports(short_flight: tuple[dict, Path], tmp_path: Path) -> None:
    _, log = short_flight
    cut = tmp_path / "cut.tlog"
    data = log.read_bytes()
    index = TlogIndex.build(log)
    middle = len(index) // 2  # cut inside a frame: a cut on a record boundary is a whole log
    cut.write_bytes(data[: int(index.offset[middle]) + int(index.length[middle]) // 2])
    out = gcs_here("report", str(cut), "--out", str(tmp_path / "r"), "--quiet")
    assert out.returncode == 0, out.stderr
    assert "truncated=True" in out.stdout
    parsed = FlightLog.load(cut)
    assert parsed.index.truncated and len(parsed.tick_t) > 10
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["figures"] == _files(FIGURES)  # the half it holds, drawn
    _figures_drawn(tmp_path / "r", FIGURES)
    r = summary["metrics"]
    assert r["ticks"] == len(parsed.tick_t)
    assert r["duration_s"] == pytest.approx(parsed.tick_t[-1] - parsed.tick_t[0], abs=1e-3)
    assert r["worst_distance_error_m"] > 0 and r["worst_bank_rad"] > 0
    assert summary["truncated"] and summary["damage"] == parsed.index.damage()
    md = (tmp_path / "r" / "summary.md").read_text()
    assert f"Damaged log: {parsed.index.damage()}" in md
    # the half it holds ends in the air: said, not passed off as a complete flight
    assert summary["cut_short"].startswith("cut short: the record ends in phase ")
    assert summary["cut_short"].endswith(", with no landing")
    assert f"note: {summary['cut_short']}" in out.stdout
    assert f"**This flight was {summary['cut_short']}**" in md


def test_corrupt_log_still_reports_and_says_what_was_skipped(
        short_flight: tuple[dict, Path], tmp_path: Path) -> None:
    m, log = short_flight
    data = bytearray(log.read_bytes())
    rng = np.random.default_rng(2)
    for k in rng.choice(len(data), 2000, replace=False):  # about one byte in 600
        data[k] ^= int(rng.integers(1, 256))
    bad = tmp_path / "corrupt.tlog"
    bad.write_bytes(bytes(data))
    out = gcs_here("report", str(bad), "--out", str(tmp_path / "r"), "--json", "--quiet")
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
    text = gcs_here("report", str(bad), "--out", str(tmp_path / "r2"), "--quiet").stdout
    assert "corrupt bytes skipped=" in text and "damaged timestamp rejected=" in text


def _files(stems: tuple[str, ...]) -> list[str]:
    return [f"{stem}.{ext}" for stem in stems for ext in FORMATS]


def _figures_drawn(folder: Path, stems: tuple[str, ...]) -> None:
    """Each figure's PNG is real, with something drawn in it (not a blank canvas)."""
    for stem in stems:
        image = plt.imread(folder / f"{stem}.png")
        assert image.shape[0] > 300 and image.shape[1] > 300, stem
        assert image[..., :3].std() > 0.05, stem


def test_plain_autopilot_log_reports_what_its_telemetry_gives(
        short_flight: tuple[dict, Path], tmp_path: Path) -> None:
    """The flight re-recorded as a plain autopilot log (the vehicles' frames only): the
    duration, the worst bank while armed and the distances between the vehicles, each
    checked against the recorded messages as pymavlink reads them."""
    m, flight = short_flight
    plain = plain_copy(flight, tmp_path / "plain.tlog")
    out = gcs_here("report", str(plain), "--out", str(tmp_path / "r"), "--json", "--quiet")
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)
    r = summary["metrics"]
    raw = [x for x in raw_messages(plain) if x.get_srcSystem() in VEHICLES]
    kinds = {"LOCAL_POSITION_NED", "ATTITUDE", "HEARTBEAT", "SYS_STATUS"}
    times = [x._timestamp for x in raw if x.get_type() in kinds]
    assert r["duration_s"] == pytest.approx(max(times) - min(times), abs=1e-3)
    assert r["duration_s"] == pytest.approx(m["duration_s"], abs=0.5)
    bank = 0.0
    for vid in VEHICLES:
        armed = False
        for x in raw:
            if x.get_srcSystem() != vid:
                continue
            if x.get_type() == "HEARTBEAT":
                armed = bool(x.base_mode & SAFETY_ARMED)
            elif x.get_type() == "ATTITUDE" and armed:
                bank = max(bank, math.acos(math.cos(x.roll) * math.cos(x.pitch)))
    assert r["worst_bank_rad"] == pytest.approx(bank, abs=1e-4)
    assert m["worst_bank_rad"] - 1e-3 <= r["worst_bank_rad"] < 0.36  # armed spans airborne
    for key in ("worst_distance_error_m", "worst_swing_rad", "worst_accel_cmd_m_s2",
                "payload_lift_m", "rope_tension_min_N"):
        assert r[key] is None, key
    assert r["ticks"] == 0 and r["phases"] == [] and r["worst_distance_error_by_phase_m"] == {}
    assert any("per-phase distance errors, payload swing or commanded accelerations" in x
               for x in summary["missing"])
    assert summary["figures"] == _files(("formation", "trajectories"))
    _figures_drawn(tmp_path / "r", ("formation", "trajectories"))
    md = (tmp_path / "r" / "summary.md").read_text()
    assert f"| duration_s | {r['duration_s']} |" in md
    assert f"| worst_bank_rad | {r['worst_bank_rad']} |" in md
    assert "| worst_swing_rad | not in this log |" in md

    # the distances drawn: every pair, each vehicle at its latest position, no desired values
    log = FlightLog.load(plain)
    fig = report._formation(log)
    assert fig is not None
    lines = fig.axes[0].get_lines()
    assert sorted(str(line.get_label()) for line in lines) == ["1-2", "1-3", "1-4", "2-3", "2-4",
                                                          "3-4"]
    positions = [x for x in raw if x.get_type() == "LOCAL_POSITION_NED"]
    t0 = min(x._timestamp for x in positions)
    line = next(line for line in lines if line.get_label() == "1-3")
    x_data, y_data = (np.asarray(a, dtype=float) for a in line.get_data())
    assert len(x_data) > 100
    for k in np.linspace(0, len(x_data) - 1, 25).astype(int):
        t = t0 + x_data[k]
        p1, p3 = ([(x.x, x.y, x.z) for x in positions if x.get_srcSystem() == vid
                   and x._timestamp <= t + 1e-6][-1] for vid in (1, 3))
        assert y_data[k] == pytest.approx(math.dist(p1, p3), abs=1e-5)
    plt.close(fig)


def test_summary_lists_the_events_one_line_per_condition(
        short_flight: tuple[dict, Path], tmp_path: Path) -> None:
    """Four vehicles switching mode together are one line with its count, not four."""
    _, log = short_flight
    out = gcs_here("report", str(log), "--out", str(tmp_path), "--quiet")
    assert out.returncode == 0, out.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    md = (tmp_path / "summary.md").read_text()
    events = md[md.index("\n## Events\n"):]
    assert "| first [s] | level | count | vehicles | event |" in events
    hold = next(line for line in summary["event_lines"] if line["text"] == "mode HOLD (was "
                "DISARMED)")
    assert hold["count"] == 4 and hold["vehicles"] == [1, 2, 3, 4] and hold["level"] == "info"
    first = min(e["t_s"] for e in summary["events"] if e["text"].endswith(": mode HOLD (was "
                                                                          "DISARMED)"))
    assert hold["first_s"] == first
    assert f"| {first} | info | 4 | 1–4 | mode HOLD (was DISARMED) |" in events
    # every logged text but the phase changes (listed apart) is counted once
    logged = [e for e in summary["events"] if not e["text"].startswith("phase: ")]
    assert sum(line["count"] for line in summary["event_lines"]) == len(logged)
    assert len(summary["event_lines"]) < len(logged) // 3
    assert "## Phases" in md and "formation at " in md


def test_an_event_storm_is_one_line_per_condition() -> None:
    """Stale telemetry on four vehicles at each of three phase changes, with different
    ages, is one line of twelve; a vehicle's own text counts for that vehicle."""
    from gcs.flightlog import event_lines
    from gcs.flightlog._events import id_ranges

    storm = [(100.0 + k + 0.01 * v, 245, 4, f"vehicle {v}: no fresh telemetry for "
              f"{0.5 + 0.1 * k + 0.01 * v:.2f} s: motion frozen")
             for k in range(3) for v in (1, 2, 3, 4)]
    texts = [(99.0, 245, 6, "phase: lifting"), *storm, (101.5, 3, 4, "EKF variance"),
             (102.5, 3, 4, "EKF variance"), (103.0, 245, 3, "vehicle 2: lost: landing")]
    lines = event_lines(texts, t0=99.0, vehicles=(1, 2, 3, 4))
    assert [(x.first_s, x.level, x.count, x.vehicles) for x in lines] == [
        (0.0, "info", 1, ()), (1.01, "warning", 12, (1, 2, 3, 4)), (2.5, "warning", 2, (3,)),
        (4.0, "error", 1, (2,))]
    assert lines[1].text == "no fresh telemetry for 0.51 s: motion frozen"  # as first seen
    assert id_ranges([7, 1, 2, 3, 4, 9, 10]) == "1–4, 7, 9, 10"


def test_unreadable_files_are_refused_in_one_line(tmp_path: Path) -> None:
    for command in ("report", "replay"):
        out = gcs_here(command, str(tmp_path))  # a folder, not a log
        assert out.returncode == 2, out.stderr
        assert out.stderr.count("\n") == 1 and str(tmp_path) in out.stderr
        assert "Traceback" not in out.stderr


def test_empty_and_garbage_logs_are_refused_in_one_line(tmp_path: Path) -> None:
    empty = tmp_path / "empty.tlog"
    empty.write_bytes(b"")
    out = gcs_here("report", str(empty), "--quiet")
    assert out.returncode == 2 and "empty file" in out.stderr
    junk = tmp_path / "junk.tlog"
    junk.write_bytes(bytes(range(256)) * 40)
    out = gcs_here("report", str(junk), "--quiet")
    assert out.returncode == 2 and "no MAVLink messages" in out.stderr
