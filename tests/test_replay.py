"""Flight replay, on a real recorded flight.

Real parts: `gcs fly` records a simulated flight (its own sim process), the
recorded bytes are read back independently with pymavlink, a plain autopilot
log is written by the real recorder, and `gcs replay` serves a real viser page.
"""

from __future__ import annotations

import html as html_lib
import re
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from pymavlink import mavutil

from gcs.flightlog import FlightLog
from gcs.link.encoder import MavlinkEncoder
from gcs.link.modes import SAFETY_ARMED, SimMode
from gcs.recorder import TlogRecorder
from tests.conftest import run_gcs
from web.replay import ReplayCursor
from web.replay_page import ReplayUi, replay_summary_html
from web.timeline import Timeline


@pytest.fixture
def flight(short_flight: tuple[dict, Path]) -> Path:
    return short_flight[1]


def _raw(path: Path) -> list:
    """Every message of the file, read by pymavlink (not by our reader)."""
    conn = mavutil.mavlink_connection(str(path), dialect="common")
    out = []
    while (m := conn.recv_match()) is not None:
        if m.get_type() != "BAD_DATA":
            out.append(m)
    return out


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_replayed_positions_are_the_recorded_ones(flight: Path) -> None:
    raw = [m for m in _raw(flight) if m.get_type() == "LOCAL_POSITION_NED"]
    cursor = ReplayCursor(FlightLog.load(flight))
    assert cursor.ids == (1, 2, 3, 4)
    checked = 0
    for t in np.linspace(cursor.start + 1.0, cursor.end, 37):
        state = cursor.state(float(t))
        for i, vid in enumerate(cursor.ids):
            before = [m for m in raw if m.get_srcSystem() == vid and m._timestamp <= t]
            expected = [before[-1].x, before[-1].y, before[-1].z]
            np.testing.assert_allclose(state.fleet.p_ned[i], expected, rtol=0, atol=1e-6)
            checked += 1
    assert checked == 37 * 4
    # the guidance tick is the latest one at or before t, with its phase and arrays
    t = cursor.start + 20.0
    k = cursor.state(t).tick
    assert cursor.log.tick_t[k] <= t < cursor.log.tick_t[k + 1]


def _page(ui: ReplayUi) -> tuple:
    """What the page holds: plot history, trail segments, slider, status tables."""
    series = ui._history.series()
    return (series, ui._trails.segments(), ui._slider.value, ui._vehicles.content,
            ui._events.content, ui._summary.content)


def test_scrubbing_backwards_gives_the_earlier_state(flight: Path) -> None:
    log = FlightLog.load(flight)
    ui = ReplayUi(log, port=_free_port())
    direct = ReplayUi(log, port=_free_port())  # jumps straight to the moment, never back
    try:
        start = ui.timeline.start
        fresh = ReplayCursor(log).state(start + 5.0)  # same moment, by a cursor never moved
        ui.seek(start + 30.0)
        late = ui.cursor.state(ui.timeline.t)
        late_page = _page(ui)
        ui.seek(start + 5.0)
        again = ui.cursor.state(ui.timeline.t)
        back_page = _page(ui)
        direct.seek(start + 5.0)
        direct_page = _page(direct)
    finally:
        ui.close()
        direct.close()
    assert late.tick > again.tick
    np.testing.assert_array_equal(again.fleet.p_ned, fresh.fleet.p_ned)
    assert again.phase == fresh.phase and again.tick == fresh.tick
    assert [e.t for e in again.events] == [e.t for e in fresh.events]
    assert len(late.events) > len(again.events)
    assert again.truth is not None  # simulation logs carry payload and ropes
    # what the page holds after the jump back: nothing of the later 25 s
    series, (segments, ages), slider = back_page[:3]
    assert slider == pytest.approx(5.0)
    assert len(series.t) > 5 and series.t[-1] <= start + 5.0
    assert len(late_page[0].t) > len(series.t)
    d_series, (d_segments, d_ages), _ = direct_page[:3]
    for name in ("t", "distance", "desired", "vx", "vy"):
        np.testing.assert_array_equal(getattr(series, name), getattr(d_series, name))
    np.testing.assert_array_equal(segments, d_segments)
    np.testing.assert_array_equal(ages, d_ages)
    assert len(segments) > 0 and not np.array_equal(segments, late_page[1][0])
    assert back_page[3:] == direct_page[3:]  # the vehicles, events and summary panels


def test_replay_shows_mode_armed_and_battery_as_the_live_table(flight: Path) -> None:
    raw = _raw(flight)
    log = FlightLog.load(flight)
    ui = ReplayUi(log, port=_free_port())
    landing = next(t for t, name in log.phase_changes() if name == "landing")
    seen_states = set()
    try:
        for t in (ui.timeline.start + 10.0, ui.timeline.start + 20.0, landing + 1.0):
            ui.seek(t)
            rows = dict(re.findall(r'data-gcs="vehicle-(\d)">(.*?)</tr>', ui._vehicles.content))
            for vid in (1, 2, 3, 4):
                cells = [html_lib.unescape(re.sub("<[^>]+>", "", c)).strip()
                         for c in re.findall(r"<td[^>]*>(.*?)</td>", rows[str(vid)])]
                hb = [m for m in raw if m.get_type() == "HEARTBEAT" and m._timestamp <= t
                      and m.get_srcSystem() == vid][-1]
                status = [m for m in raw if m.get_type() == "SYS_STATUS" and m._timestamp <= t
                          and m.get_srcSystem() == vid][-1]
                assert cells[2] == SimMode(hb.custom_mode).name
                assert cells[3] == ("yes" if hb.base_mode & SAFETY_ARMED else "no")
                assert cells[4] == f"{status.battery_remaining:.0f}"
                assert float(cells[8]) == pytest.approx(t - hb._timestamp, abs=0.051)
                seen_states.add(cells[1].split(" ", 1)[1])
    finally:
        ui.close()
    assert seen_states == {"ok", "landing"}  # from the modes, as the live page derives them


def test_each_phase_change_is_one_event(flight: Path) -> None:
    cursor = ReplayCursor(FlightLog.load(flight))
    phases = [e.text for e in cursor.events if "phase:" in e.text]
    assert phases == [f"phase: {name}" for _, name in cursor.log.phase_changes()]
    assert any("mode OFFBOARD" in e.text for e in cursor.events)  # other texts stay


def test_timeline_plays_pauses_and_clamps() -> None:
    tl = Timeline(100.0, 110.0)
    assert tl.advance(1.0) == 100.0  # paused
    tl.speed = 100.0
    assert tl.speed == 16.0
    tl.speed = 0.01
    assert tl.speed == 0.25
    tl.speed = 4.0
    tl.play()
    assert tl.advance(1.0) == pytest.approx(104.0)
    tl.pause()
    assert tl.advance(1.0) == pytest.approx(104.0)
    tl.play()
    assert tl.advance(10.0) == 110.0 and not tl.playing
    tl.seek(-5.0)
    assert tl.t == 100.0


def test_plain_autopilot_log_opens_and_says_what_is_missing(flight: Path,
                                                            tmp_path: Path) -> None:
    plain = tmp_path / "autopilot.tlog"
    rec = TlogRecorder(plain, encoder=MavlinkEncoder(system_id=255, component_id=190),
                       epoch=0.0)
    for m in _raw(flight):
        if m.get_srcSystem() in (1, 2, 3, 4):  # vehicles only: no GCS internals
            rec.frame(m._timestamp, m.get_msgbuf())
    rec.close()
    log = FlightLog.load(plain)
    assert log.team is None and len(log.tick_t) == 0
    assert any("guidance internals" in m for m in log.missing)
    cursor = ReplayCursor(log)
    state = cursor.state(cursor.start + 10.0)
    assert np.isfinite(state.fleet.p_ned).all() and state.phase is None
    assert state.truth is None
    html = replay_summary_html(state, start=cursor.start, name="x", missing=log.missing)
    assert "guidance internals" in html and "team header" in html
    ui = ReplayUi(log, port=_free_port())  # draws without edges, ticks or truth
    try:
        ui.seek(cursor.start + 20.0)
    finally:
        ui.close()


def test_replay_command_serves_the_page_without_controls(flight: Path,
                                                         tmp_path: Path) -> None:
    bad = tmp_path / "bad.tlog"
    bad.write_bytes(b"not a log at all" * 10)
    out = run_gcs("replay", str(bad))
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1 and "error" in out.stderr

    port = _free_port()
    proc = subprocess.Popen([sys.executable, "-m", "gcs", "replay", str(flight), "--port",
                             str(port)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        line = ""
        deadline = time.monotonic() + 30
        while "GCS replay:" not in line and time.monotonic() < deadline:
            line = proc.stdout.readline()  # type: ignore[union-attr]
        assert f"http://127.0.0.1:{port}" in line
        with urllib.request.urlopen(f"http://127.0.0.1:{port}", timeout=5) as r:
            assert r.status == 200
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=10) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()

    ui = ReplayUi(FlightLog.load(flight), port=_free_port())
    try:
        labels = {h.label for h in ui.server.gui._gui_input_handle_from_uuid.values()}
    finally:
        ui.close()
    assert {"Play", "Pause", "Speed", "Time (s)", "Jump to event"} <= labels
    assert not labels & {"ABORT", "Take control", "Arm", "Take off", "Land"}
