"""Flight replay, on a real recorded flight.

Real parts: `gcs fly` records a simulated flight (its own sim process), the
recorded bytes are read back independently with pymavlink, a plain autopilot
log is written by the real recorder, `gcs replay` serves a real viser page,
and a websocket client reads that page as a browser does (what it is sent,
decoded) and clicks and chooses as a browser does.
"""

from __future__ import annotations

import html as html_lib
import queue
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, cast

import numpy as np
import pytest
import viser
from viser import _messages as viser_messages

from gcs.app import free_tcp_port
from gcs.flightlog import FlightLog, TlogIndex
from gcs.wire import SAFETY_ARMED, MavlinkEncoder, heartbeat_mode_text, mavlink
from tests.support.commands import gcs_here
from tests.support.logfiles import ardupilot_log, plain_copy, raw_messages, with_frame
from web._actions import OperatorActions
from web._control_lock import ControlLock
from web._panel import ControlPanel
from web._replay import ReplayCursor
from web._replay_page import ReplayUi, replay_summary_html
from web._timeline import Timeline
from web.wireviewer import WireViewer

TIMELINE = {"Play", "Pause", "Speed", "Time (s)", "Event", "Jump to event", "Previous event",
            "Next event"}
"""The replay's own controls (what a viewer of the replay page must get)."""


@pytest.fixture
def flight(short_flight: tuple[dict, Path]) -> Path:
    return short_flight[1]


class PageViewer(WireViewer):
    """A websocket viewer of a viser page (:class:`web.wireviewer.WireViewer`) that also keeps
    the GUI it is sent, and clicks buttons and picks dropdown values as the browser does.

    ``widgets`` holds every GUI element the viewer was sent, by id: its message type
    and its properties (label, options, content...) with every later update applied.
    """

    def __init__(self, port: int) -> None:
        self.widgets: dict[str, dict[str, object]] = {}
        super().__init__(port)
        self.report_camera((-3.0, -1.0, -2.0), (0.0, 0.0, 0.0))  # viser counts it then

    def _apply(self, m: dict) -> None:
        super()._apply(m)
        kind = m["type"]
        if kind.startswith("Gui") and "props" in m and "uuid" in m:
            self.widgets[m["uuid"]] = {"type": kind, "value": m.get("value"), **m["props"]}
        elif kind == "GuiUpdateMessage" and m["uuid"] in self.widgets:
            self.widgets[m["uuid"]].update(m["updates"])
        elif kind == "GuiRemoveMessage":
            self.widgets.pop(m["uuid"], None)

    def texts(self) -> set[str]:
        """Every label, option and HTML or Markdown text the viewer was sent (non-empty)."""
        out: set[str] = set()
        with self._lock:
            for w in self.widgets.values():
                out.update(str(x) for x in (w.get("label"), w.get("content"), w.get("_markdown"))
                           if x)
                out.update(str(x) for x in w.get("options") or ())  # type: ignore[attr-defined]
        return out

    def uuid(self, label: str, timeout: float = 30.0) -> str:
        """The id of the element labelled ``label`` (exactly one must exist), once the page
        has sent it: a page built on a busy machine sends its controls after the viewer
        connected."""
        def labelled() -> list[str]:
            with self._lock:
                return [u for u, w in self.widgets.items() if w.get("label") == label]

        self.until(lambda: bool(labelled()), timeout)
        (found,) = labelled()
        return found

    def click(self, label: str) -> None:
        self.send(viser_messages.GuiUpdateMessage(self.uuid(label), {"value": True}))

    def choose(self, label: str, value: str) -> None:
        self.send(viser_messages.GuiUpdateMessage(self.uuid(label), {"value": value}))

    @staticmethod
    def until(what: Callable[[], bool], timeout: float = 10.0) -> bool:
        """Whether ``what`` came true within ``timeout`` seconds (the page answers a
        viewer on viser's threads)."""
        deadline = time.monotonic() + timeout
        while not what():
            if time.monotonic() > deadline:
                return False
            time.sleep(0.02)
        return True

    def settled_texts(self, quiet: float = 0.5, timeout: float = 30.0,
                      having: frozenset[str] = frozenset()) -> set[str]:
        """:meth:`texts` once it holds ``having`` and nothing new arrived for ``quiet``
        seconds; fails if the page still changes after ``timeout`` seconds (a page that never
        rests would hang the test). ``having``: what the page is known to send, so that a
        page built late on a busy machine is not taken as settled before it began."""
        deadline = time.monotonic() + timeout
        if not self.until(lambda: having <= self.texts(), timeout):
            pytest.fail(f"the page did not send {sorted(having - self.texts())} "
                        f"in {timeout:.0f} s")
        last: set[str] | None = None
        while (now := self.texts()) != last:
            if time.monotonic() > deadline:
                pytest.fail(f"the page kept changing for {timeout:.0f} s")
            last = now
            time.sleep(quiet)
        return now


@contextmanager
def viewer_of(port: int, timeout: float = 10.0) -> Iterator[PageViewer]:
    viewer = PageViewer(port)
    try:
        assert viewer.until(lambda: bool(viewer.widgets), timeout), "the page sent nothing"
        yield viewer
    finally:
        viewer.close()


class OutputLines:
    """A process's output, read line by line on a thread, so that waiting for a line can
    have a deadline (a readline on the pipe would wait for ever on a silent process)."""

    def __init__(self, stream: IO[str]) -> None:
        self._lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._read, args=(stream,), daemon=True).start()

    def _read(self, stream: IO[str]) -> None:
        for line in stream:
            self._lines.put(line.rstrip("\n"))
        self._lines.put(None)  # the process closed its output

    def next(self, deadline: float, what: str) -> str | None:
        """The next line, None once the output ended; fails, naming ``what`` it waited
        for, if none came by ``deadline`` (time.monotonic())."""
        try:
            return self._lines.get(timeout=max(0.0, deadline - time.monotonic()))
        except queue.Empty:
            pytest.fail(f"timed out waiting for {what}")

    def rest(self, deadline: float, what: str) -> list[str]:
        """Every line up to the end of the output, which must come by ``deadline``."""
        out = []
        while (line := self.next(deadline, what)) is not None:
            out.append(line)
        return out


def wait_or_tell(proc: subprocess.Popen[str], seconds: float, err: IO[str]) -> int:
    """``proc``'s exit status within ``seconds``; else a failure that shows where each of
    its threads stood (``gcs`` dumps them on SIGUSR1) and its stderr."""
    try:
        return proc.wait(timeout=seconds)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGUSR1)
        time.sleep(2.0)
        proc.kill()
        proc.wait()
        err.seek(0)
        pytest.fail(f"gcs did not stop within {seconds:g} s of Ctrl-C; its stderr:\n{err.read()}")


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextmanager
def served(path: Path, *, sigint_ignored: bool = False) -> Iterator[tuple[int, list[str]]]:
    """``gcs replay PATH`` in its own process: its port, and its stdout lines from its
    address on, once stopped (by Ctrl-C, which must end it with status 0).
    ``sigint_ignored``: started as a non-interactive shell starts a command in the
    background, with SIGINT ignored."""
    port = free_tcp_port()
    with tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen([sys.executable, "-m", "gcs", "replay", str(path), "--port",
                                 str(port), "--quiet"], stdout=subprocess.PIPE, stderr=err,
                                text=True, preexec_fn=_ignore_sigint if sigint_ignored else None)
        assert proc.stdout is not None
        out = OutputLines(proc.stdout)
        lines: list[str] = []
        try:
            deadline = time.monotonic() + 60
            while not lines or "GCS replay:" not in lines[-1]:
                line = out.next(deadline, "gcs replay's address")
                if line is None:
                    err.seek(0)
                    pytest.fail(f"gcs replay ended before its address: {err.read()}")
                lines.append(line)
            assert lines[-1].startswith(f"GCS replay: http://127.0.0.1:{port}")
            del lines[:-1]  # viser's banner
            yield port, lines
            proc.send_signal(signal.SIGINT)
            assert wait_or_tell(proc, 20, err) == 0
            lines += [line for line in out.rest(time.monotonic() + 10, "gcs replay's output")
                      if not line.startswith("(viser)")]
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()


def test_ctrl_c_stops_a_replay_started_in_the_background_of_a_script(flight: Path) -> None:
    """``gcs replay LOG &`` in a shell script starts with SIGINT ignored; Ctrl-C (SIGINT)
    must stop it all the same (it ran on for ever: the CI's background runs saw it)."""
    with served(flight, sigint_ignored=True) as (_port, lines):
        pass
    assert lines[1:] == ["stopping…"]


def test_the_waits_on_a_page_and_a_process_end() -> None:
    """A page that never rests and a process that never prints fail these tests, in time,
    rather than hang them."""
    server = viser.ViserServer(host="127.0.0.1", port=free_tcp_port(), verbose=False)
    ticking = server.gui.add_markdown("0")
    stop = threading.Event()

    def tick() -> None:
        while not stop.wait(0.1):
            ticking.content = f"{time.monotonic():.3f}"

    ticker = threading.Thread(target=tick, daemon=True)
    ticker.start()
    try:
        with viewer_of(server.get_port()) as viewer, \
                pytest.raises(pytest.fail.Exception, match="the page kept changing for 2 s"):
            viewer.settled_texts(timeout=2.0)
    finally:
        stop.set()
        ticker.join()
        server.stop()
    silent = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert silent.stdout is not None
        start = time.monotonic()
        with pytest.raises(pytest.fail.Exception, match="timed out waiting for a line"):
            OutputLines(silent.stdout).next(start + 0.5, "a line")
        assert time.monotonic() - start < 5.0
    finally:
        silent.kill()
        silent.wait()


def test_replayed_positions_are_the_recorded_ones(flight: Path) -> None:
    raw = [m for m in raw_messages(flight) if m.get_type() == "LOCAL_POSITION_NED"]
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
    ui = ReplayUi(log, port=free_tcp_port())
    direct = ReplayUi(log, port=free_tcp_port())  # jumps straight to the moment, never back
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
    raw = raw_messages(flight)
    log = FlightLog.load(flight)
    ui = ReplayUi(log, port=free_tcp_port())
    landing = next(t for t, name in log.phase_changes() if name == "landing")
    seen_states = set()
    try:
        for t in (ui.timeline.start + 10.0, ui.timeline.start + 20.0, landing + 1.0):
            ui.seek(t)
            rows = _vehicle_rows(ui._vehicles.content)
            for vid in (1, 2, 3, 4):
                cells = rows[vid]
                hb = [m for m in raw if m.get_type() == "HEARTBEAT" and m._timestamp <= t
                      and m.get_srcSystem() == vid][-1]
                status = [m for m in raw if m.get_type() == "SYS_STATUS" and m._timestamp <= t
                          and m.get_srcSystem() == vid][-1]
                assert cells[2] == heartbeat_mode_text(hb.autopilot, hb.custom_mode)
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
    log = FlightLog.load(plain_copy(flight, tmp_path / "autopilot.tlog"))
    assert log.team is None and len(log.tick_t) == 0
    assert any("guidance internals" in m for m in log.missing)
    cursor = ReplayCursor(log)
    state = cursor.state(cursor.start + 10.0)
    assert np.isfinite(state.fleet.p_ned).all() and state.phase is None
    assert state.truth is None
    html = replay_summary_html(state, start=cursor.start, name="x", missing=log.missing)
    assert "guidance internals" in html and "team header" in html
    ui = ReplayUi(log, port=free_tcp_port())  # draws without edges, ticks or truth
    try:
        ui.seek(cursor.start + 20.0)
    finally:
        ui.close()


def test_replay_command_serves_the_page_without_controls(flight: Path,
                                                         tmp_path: Path) -> None:
    """What reaches a viewer of `gcs replay`: the timeline, and none of the live page's
    operator controls (those are built per viewer, so only a viewer can tell)."""
    bad = tmp_path / "bad.tlog"
    bad.write_bytes(b"not a log at all" * 10)
    out = gcs_here("replay", str(bad))
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1 and "error" in out.stderr

    live = viser.ViserServer(host="127.0.0.1", port=free_tcp_port(), verbose=False)
    try:  # what the live page gives each viewer: its control panel
        live.on_client_connect(lambda client: ControlPanel(
            client, cast(OperatorActions, object()), ControlLock(),
            on_control_change=lambda: None))
        with viewer_of(live.get_port()) as viewer:
            controls = viewer.settled_texts(having=frozenset({"Take control"}))
    finally:
        live.stop()
    assert {"ABORT: hold, then land", "Take control", "guidance on"} <= controls
    assert any("data-gcs-pad" in text for text in controls)  # the sticks

    with served(flight) as (port, lines), viewer_of(port) as viewer:
        page = viewer.settled_texts(having=frozenset(TIMELINE))
    assert page >= TIMELINE
    view = {"View", "camera follows team", "Centre on team"}  # the camera's: in both pages
    assert view <= page and not (page & controls) - view, page & controls
    assert not any("data-gcs-pad" in text for text in page)
    assert lines[1:] == ["stopping…"]  # a whole log: no note


@pytest.mark.parametrize("damage", ["cut", "flipped bytes"])
def test_replay_of_a_damaged_log_says_what_could_not_be_read(flight: Path, tmp_path: Path,
                                                             damage: str) -> None:
    data = bytearray(flight.read_bytes())
    index = TlogIndex.build(flight)
    if damage == "cut":  # inside a frame: a cut on a record boundary is a whole log
        middle = len(index) // 2
        data = data[: int(index.offset[middle]) + int(index.length[middle]) // 2]
    else:
        rng = np.random.default_rng(5)
        for k in rng.choice(len(data), 300, replace=False):
            data[k] ^= int(rng.integers(1, 256))
    bad = tmp_path / "damaged.tlog"
    bad.write_bytes(bytes(data))
    note = FlightLog.load(bad).index.damage()
    assert note is not None
    with served(bad) as (port, lines), viewer_of(port) as viewer:
        shown = f"damaged log: {html_lib.escape(note)}</li>"
        assert viewer.until(lambda: any('data-gcs="missing"' in t and shown in t
                                    for t in viewer.texts()))
    assert lines[1:] == [f"note: {note}", "stopping…"]
    if damage == "cut":
        assert "truncated=True" in note
        report = gcs_here("report", str(bad), "--out", str(tmp_path / "r"), "--quiet")
        assert f"note: {note}" in report.stdout.splitlines()  # one wording for both
    else:
        assert "corrupt bytes skipped=0" not in note


def _event_log(flight: Path, tmp_path: Path) -> tuple[Path, float, float]:
    """The flight with a warning and a notice from vehicle 2 (real STATUSTEXT frames),
    20 s and 21 s in; returns the log and the two moments."""
    enc = MavlinkEncoder(system_id=2, component_id=1)
    start = float(TlogIndex.build(flight).t.min())
    warn_t, notice_t = start + 20.0, start + 21.0
    path = with_frame(flight, tmp_path / "warned.tlog", warn_t, enc.encode(
        enc.mav.statustext_encode(mavlink.MAV_SEVERITY_WARNING, b"rope snag")))
    path = with_frame(path, tmp_path / "noted.tlog", notice_t, enc.encode(
        enc.mav.statustext_encode(mavlink.MAV_SEVERITY_NOTICE, b"payload seen")))
    return path, warn_t, notice_t


def test_a_viewer_steps_and_jumps_through_the_events(flight: Path, tmp_path: Path) -> None:
    path, warn_t, notice_t = _event_log(flight, tmp_path)
    log = FlightLog.load(path)
    ui = ReplayUi(log, name="warned", port=free_tcp_port())
    try:
        events = ui.cursor.events
        assert [(e.kind, e.text) for e in events if e.t in (warn_t, notice_t)] == \
            [("warning", "2: rope snag"), ("text", "2: payload seen")]
        change = next(e for e in events if e.text == "phase: formation")
        k = events.index(change)
        with viewer_of(ui.server.get_port()) as viewer:
            viewer.choose("Speed", "4x")
            viewer.until(lambda: ui.timeline.speed == 4.0)
            assert ui.timeline.speed == 4.0

            def lands_on(t: float) -> None:
                viewer.until(lambda: ui.timeline.t == t)
                assert ui.timeline.t == t

            def pick(ending: str) -> None:
                options = viewer.widgets[viewer.uuid("Event")]["options"]
                viewer.choose("Event", next(o for o in options if o.endswith(ending)))  # type: ignore[attr-defined]
                viewer.click("Jump to event")

            pick("phase: formation")
            lands_on(change.t)  # exactly the tick where the phase changed
            assert viewer.until(lambda: any(  # and the viewer is shown that tick's phase
                'data-gcs="phase" style="font-size:1.2em">formation<' in t
                for t in viewer.texts()))
            viewer.click("Next event")
            lands_on(events[k + 1].t)
            viewer.click("Previous event")
            lands_on(change.t)
            ui.seek((change.t + events[k + 1].t) / 2)  # between two events: back to the change
            viewer.click("Previous event")
            lands_on(change.t)
            ui.seek((events[k - 1].t + change.t) / 2)  # and forwards onto it
            viewer.click("Next event")
            lands_on(change.t)

            pick("rope snag")
            lands_on(warn_t)
            warned = re.compile(r'<div style="color:#e67e22"><span[^>]*>[^<]*</span> 2: rope snag<')
            assert viewer.until(lambda: any(warned.search(t) for t in viewer.texts()))
    finally:
        ui.close()


def test_an_ardupilot_team_replays_with_a_vehicle_that_sent_no_position(tmp_path: Path) -> None:
    """ArduCopters whose local origins differ are placed from GPS; a vehicle without any
    position still has its row (mode, armed, battery) and no place in the scene."""
    log = FlightLog.load(ardupilot_log(tmp_path / "ap.tlog", shared_origin=False))
    ui = ReplayUi(log, name="ap", port=free_tcp_port())
    try:
        assert ui.timeline.duration == pytest.approx(5.9, abs=1e-3)
        ui.seek(ui.timeline.start + 3.05)  # the 31st sample (k = 30) is the latest
        state = ui.cursor.state(ui.timeline.t)
        rows = _vehicle_rows(ui._vehicles.content)
        summary = html_lib.unescape(ui._summary.content)
    finally:
        ui.close()
    p = state.fleet.p_ned
    np.testing.assert_allclose(p[1:3, 1] - p[0, 1], [3.0, 6.0], atol=0.02)  # 3 m apart east
    assert np.isnan(p[3]).all()
    for vid in (1, 2, 3, 4):
        assert rows[vid][2:5] == ["GUIDED", "yes", f"{90 - 30 // 20}"]
    assert rows[4][1].endswith("stale") and rows[4][6] == "–"  # no position, no altitude
    assert rows[1][1].endswith("ok")
    assert "vehicle positions from vehicle 4" in summary
    assert "origins differ by up to 6.0 m" in summary

    alone = FlightLog.load(ardupilot_log(tmp_path / "attitude.tlog", shared_origin=False,
                                         placed=()))
    assert sorted(alone.tracks) == [1, 2, 3, 4]
    assert alone.telemetry_metrics()["duration_s"] == pytest.approx(5.9, abs=1e-3)
    cursor = ReplayCursor(alone)
    assert cursor.end - cursor.start == pytest.approx(5.9, abs=1e-3)  # not 0..0 s
    assert cursor.state(cursor.start + 2.0).fleet.modes == ("GUIDED",) * 4


def _vehicle_rows(table: str) -> dict[int, list[str]]:
    """The vehicles table's cells as text, by vehicle id."""
    rows = dict(re.findall(r'data-gcs="vehicle-(\d+)">(.*?)</tr>', table))
    return {int(vid): [html_lib.unescape(re.sub("<[^>]+>", "", c)).strip()
                       for c in re.findall(r"<td[^>]*>(.*?)</td>", row)]
            for vid, row in rows.items()}
