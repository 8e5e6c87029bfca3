"""``gcs replay FILE --export flight.html``: the replay as one file, opened offline.

The short flight (``short_flight``, flown once per session) is exported by the
real command. The file must stand alone: one HTML file, no external address,
within the size the issue allows (10 MB for 90 s, so pro rata here). Headless
Chromium then opens it from a ``file://`` URL with every other request
aborted (and counted: none may be attempted), scrubs to a moment of the
formation phase and checks that the team is where the log has it: in what the
page's script shows, and in viser's recorded scene at the moment viser's
playback was moved to (decoded from the file, as the page decodes it), which is
also where ``gcs replay``'s live page puts it at that moment. The page must
raise no JavaScript error.
"""

from __future__ import annotations

import base64
import re
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import msgspec
import numpy as np
import pytest
import zstandard

from gcs.app import free_tcp_port
from gcs.flightlog import FlightLog
from tests.support.commands import gcs_here
from web._export import EXPORT_RATE_HZ
from web._replay import ReplayCursor
from web._replay_page import ReplayUi
from web.wireviewer import WireViewer, _resolve

MAX_BYTES_PER_S = 10e6 / 90.0
"""The issue's bound: a 90 s flight in at most 10 MB."""
SCENE = "/team/vehicles"


@pytest.fixture(scope="module")
def exported(short_flight: tuple[dict, Path],
             tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, str]:
    """(the .tlog, the exported file, what the command printed)."""
    log = short_flight[1]
    out = tmp_path_factory.mktemp("export") / "flight.html"
    done = gcs_here("replay", str(log), "--export", str(out), "--quiet")
    assert done.returncode == 0, done.stdout + done.stderr
    return log, out, done.stdout


def recording(page: str) -> list[tuple[float, dict[str, Any]]]:
    """viser's recorded scene embedded in the page: (time, message), arrays in place."""
    found = re.search(r'__VISER_EMBED_DATA__="([^"]+)"', page)
    assert found, "no viser recording in the page"
    data = base64.b64decode(found.group(1))
    size = int.from_bytes(data[:8], "little")
    inner = zstandard.ZstdDecompressor().decompress(data[8:], max_output_size=size)
    length = int.from_bytes(inner[:8], "little")
    doc = msgspec.msgpack.decode(inner[8:8 + length])
    raw = np.frombuffer(inner, dtype=np.uint8)
    buffers, offset = [], 8 + length
    for n in doc["binaryBufferLengths"]:
        offset += -offset % 8
        buffers.append(raw[offset:offset + n])
        offset += n
    return [(t, _resolve(m, buffers)) for t, m in doc["messages"]]


def recorded_vehicles(messages: list[tuple[float, dict[str, Any]]], at: float) -> np.ndarray:
    """The vehicles' positions in the recorded scene at playback time ``at`` (n, 3)."""
    positions = None
    for t, m in messages:
        if t > at:
            break
        if m.get("name") != SCENE:
            continue
        if "props" in m:
            positions = m["props"]["batched_positions"]
        elif m.get("type") == "SceneNodeUpdateMessage" and "batched_positions" in m["updates"]:
            positions = m["updates"]["batched_positions"]
    assert positions is not None, f"the recording has no {SCENE} at {at} s"
    return np.asarray(positions, dtype=float).reshape(-1, 3)


def scene_positions(viewer: WireViewer, expect: np.ndarray, timeout: float = 10.0) -> np.ndarray:
    """The vehicles' positions the viewer has: once they are ``expect`` (the node arrives
    created, then updated, in windows a busy machine may space out), or as they stand after
    ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while True:
        shown = np.asarray(viewer.wait_for(SCENE)["batched_positions"],
                           dtype=float).reshape(-1, 3)
        if np.allclose(shown, expect, atol=1e-6) or time.monotonic() > deadline:
            return shown
        time.sleep(0.05)


def live_replay(log: Path, at: float, expect: np.ndarray) -> np.ndarray:
    """The vehicles' positions that ``gcs replay``'s page sends a viewer at log time ``at``
    (:func:`scene_positions`)."""
    ui = ReplayUi(FlightLog.load(log), port=free_tcp_port())
    try:
        ui.seek(at)
        viewer = WireViewer(ui.server.get_port())
        try:
            return scene_positions(viewer, expect)
        finally:
            viewer.close()
    finally:
        ui.close()


def test_export_is_one_self_contained_file(exported: tuple[Path, Path, str]) -> None:
    log, out, printed = exported
    assert f"wrote {out}" in printed and "no server" in printed, printed
    assert sorted(p.name for p in out.parent.iterdir()) == ["flight.html"]  # nothing beside it
    page = out.read_text(encoding="utf-8")
    cursor = ReplayCursor(FlightLog.load(log))
    duration = cursor.end - cursor.start
    size = out.stat().st_size
    print(f"export of {duration:.1f} s: {size / 1e6:.2f} MB")
    assert size <= MAX_BYTES_PER_S * duration, f"{size} bytes for {duration:.1f} s"
    # nothing to fetch: no external script, style, image or link, no fetch or socket
    assert not re.search(r"""(src|href)\s*=\s*["']?\s*(https?:)?//""", page, re.I)
    assert not re.search(r"""url\(\s*["']?(https?:)?//|@import""", page, re.I)
    overlay = page[page.index("__GCS_EXPORT__"):]
    assert not re.search(r"\bfetch\(|XMLHttpRequest|WebSocket|EventSource", overlay)
    assert page.count("<html") == 1 and "__VISER_EMBED_DATA__" in page


def test_export_to_a_missing_folder_is_one_line(short_flight: tuple[dict, Path],
                                                tmp_path: Path) -> None:
    out = tmp_path / "no such folder" / "flight.html"
    done = gcs_here("replay", str(short_flight[1]), "--export", str(out), "--quiet")
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.strip().splitlines() == [
        f"gcs replay: error: {out.parent}: no such directory"], done.stderr
    assert not out.parent.exists()


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    from tests.browser.test_live_demo import headless_chromium  # skips without chromium

    yield from headless_chromium(tmp_path_factory)


@pytest.fixture(scope="module")
def opened(browser: Any, exported: tuple[Path, Path, str]) -> Iterator[tuple[Any, dict]]:
    """The exported file in a browser with the network cut: (page, what it attempted)."""
    _, out, _ = exported
    context = browser.new_context(viewport={"width": 1400, "height": 800})
    seen: dict[str, list[str]] = {"requests": [], "blocked": [], "errors": []}

    def route(r: Any) -> None:
        url = r.request.url
        if url.startswith(("file:", "data:", "blob:")):
            r.continue_()
        else:
            seen["blocked"].append(url)
            r.abort()

    context.route("**/*", route)
    page = context.new_page()
    page.on("request", lambda r: seen["requests"].append(r.url))
    page.on("pageerror", lambda e: seen["errors"].append(f"page error: {e}"))
    page.on("console", lambda m: seen["errors"].append(f"console: {m.text}")
            if m.type == "error" else None)
    page.goto(out.as_uri())
    page.wait_for_function("window.gcsExport && window.gcsExport.ready", timeout=60_000)
    page.wait_for_function("gcsExport.synced()", timeout=60_000)
    # headless chromium renders WebGL in software, and viser says so in a notification
    # over the panel's corner: closed, as a user would
    toast = page.locator("#webgl-software-rendering .mantine-Notification-closeButton")
    if toast.count():
        toast.click()
        toast.wait_for(state="detached")
    yield page, seen
    context.close()


def settle(page: Any) -> None:
    """Until viser's playback shows the frame the page's script shows."""
    page.wait_for_function("gcsExport.synced()", timeout=10_000)


def test_exported_page_scrubs_to_the_logged_positions(
        opened: tuple[Any, dict], exported: tuple[Path, Path, str], tmp_path: Path) -> None:
    from tests.browser.test_live_demo import scene_pixels

    page, seen = opened
    log_path, out, _ = exported
    cursor = ReplayCursor(FlightLog.load(log_path))
    start = cursor.start
    formation = [t for t, name in cursor.log.phase_changes() if name == "formation"]
    assert formation, "the short flight has a formation phase"
    target = formation[0] - start + 2.33  # between two frames

    page.evaluate(f"gcsExport.seek({target})")
    settle(page)
    state = page.evaluate("gcsExport.state()")
    frame = state["frame"]
    assert frame == int(target * EXPORT_RATE_HZ)
    at = start + frame / EXPORT_RATE_HZ
    logged = cursor.fleet(at).p_ned
    # the page's script: the positions it shows are the log's at that frame, to the mm
    np.testing.assert_allclose(np.array(state["positions"], dtype=float), logged, atol=6e-4)
    assert state["phase"] == "formation"
    assert page.locator("[data-gcs=replay-time]").inner_text() == f"{frame / EXPORT_RATE_HZ:.2f}"
    # viser's playback moved to the same frame, where its recorded scene has the team
    shown = page.evaluate("gcsExport.viserTime()")
    assert abs(shown - (frame + 0.5) / EXPORT_RATE_HZ) < 1e-3, shown
    scene = recording(out.read_text(encoding="utf-8"))
    np.testing.assert_allclose(recorded_vehicles(scene, shown), logged, atol=1e-4)
    # ... where the live replay page, at that moment, has them
    recorded = recorded_vehicles(scene, shown)
    np.testing.assert_allclose(recorded, live_replay(log_path, at, recorded), atol=1e-6)

    # ... and drew it: the vehicles' ok green on the 3-D view (the panel folded: its table
    # has green dots), and the view changes when the play head moves on
    page.locator("#gcs-x-panel button[title='fold the panel']").click()
    time.sleep(1.0)
    green, magenta = scene_pixels(page, tmp_path / "export-scene.png")
    print(f"exported scene at {frame / EXPORT_RATE_HZ:.1f} s: {green} ok-green, {magenta} "
          f"payload-magenta pixels ({tmp_path / 'export-scene.png'})")
    assert green > 200 and magenta > 20, (green, magenta)
    page.locator("#gcs-x-panel button[title='fold the panel']").click()

    assert seen["blocked"] == [], seen["blocked"]
    assert all(u.startswith(("file:", "data:", "blob:")) for u in seen["requests"]), \
        seen["requests"]
    assert seen["errors"] == [], seen["errors"]


def test_exported_timeline_scrubs_plays_and_jumps(opened: tuple[Any, dict],
                                                  exported: tuple[Path, Path, str]) -> None:
    page, seen = opened
    duration = page.evaluate("gcsExport.duration")
    # the scrubber: a click a quarter of the way along is a quarter of the flight
    scrubber = page.locator("[data-gcs=export-scrubber]")
    box = scrubber.bounding_box()
    page.mouse.click(box["x"] + 1 + 0.25 * (box["width"] - 2), box["y"] + box["height"] / 2)
    settle(page)
    assert abs(page.evaluate("gcsExport.time()") - 0.25 * duration) < 0.01 * duration
    # space plays (viser's own space handler must not start its own clock) and pauses
    page.locator("body").press("Space")
    wall0 = time.monotonic()
    t0 = page.evaluate("gcsExport.time()")
    time.sleep(1.5)
    assert page.evaluate("gcsExport.playing()")
    page.locator("body").press("Space")
    t1 = page.evaluate("gcsExport.time()")
    wall = time.monotonic() - wall0  # a loaded machine's key presses take their time
    # real time: at least most of the sleep, at most the wall time the reads spanned
    assert 0.5 < t1 - t0 < wall + 0.5, (t0, t1, wall)
    settle(page)
    time.sleep(0.5)
    assert page.evaluate("gcsExport.time()") == t1 and page.evaluate("gcsExport.synced()")
    # the next event is a later event's time, the previous one an earlier one's
    page.locator("[data-gcs=export-next]").click()
    t2 = page.evaluate("gcsExport.time()")
    page.locator("[data-gcs=export-prev]").click()
    t3 = page.evaluate("gcsExport.time()")
    assert t2 > t1 and t3 < t2, (t1, t2, t3)
    # the plots: one chart per figure, with a cursor that follows
    page.get_by_role("button", name="Plots").click()
    assert page.locator("[data-gcs=export-chart]").count() == 4
    assert seen["errors"] == [], seen["errors"]
