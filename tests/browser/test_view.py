"""What a viewer sees in a real browser: the camera on the team, the events grouped.

The paper's team flies in formation in lockstep with the real simulator
(``tests.support.flights.in_formation``) and is flown about 3 m from the
origin; its page (:class:`web.WebUi`) is served in this process and viewed by
headless Chromium (Playwright). Each viewer's camera is read on the server
(``client.camera``: what the browser reports, after it applied what it was
sent). The tests share the flight and run in file order: a viewer joins far
from the origin, centres on the team, then the vehicles' links are cut four at a
time, three times over, and the page shows that storm as one line.
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
import viser

from gcs.app import GcsApp, free_tcp_port
from tests.browser.test_live_demo import (
    SCENE_GREEN_MIN,
    freshness,
    headless_chromium,
    is_fresh,
    page_url,
    scene_pixels,
    wait_for,
)
from tests.support.flights import break_vehicle, in_formation, sim_sleep
from web import WebUi
from web._browser_script import RECONNECT_AFTER_S
from web.wireviewer import WireViewer

AWAY = 3.0
"""How far from the origin the team is when a viewer joins, m."""
ON_TEAM = 0.3
"""A camera looks at the team when the point it looks at is this close to the team's
centroid, horizontally, m."""
FAR = 10.0
"""... and stands no farther than this from it, m."""
PACE = "3"
"""Sim seconds per wall second of the flight the page shows."""


@pytest.fixture(scope="module")
def flight() -> Iterator[GcsApp]:
    """The team in formation, at least :data:`AWAY` from the origin, nearly still; flown at
    :data:`PACE` (at full speed the page took the GCS's ticks at tens a second, and the
    viewer's input waited behind them on a loaded machine)."""
    with in_formation(speed=PACE) as app:
        while np.hypot(*centroid(app)[:2]) < 1.0:  # diagonally: away from both fences
            app.operator.set_sticks(0.6, 0.6, 0.0, now=app.clock.now(), source="test")
            sim_sleep(app, 0.25)
        app.operator.set_sticks(0.0, 0.0, 0.0, now=app.clock.now(), source="test")
        while np.hypot(*centroid(app)[:2]) < AWAY:  # it coasts on (c1 = 0.17/s brakes gently)
            sim_sleep(app, 0.25)
        yield app


@pytest.fixture(scope="module")
def page_ui(flight: GcsApp) -> Iterator[WebUi]:
    ui = WebUi(flight, port=free_tcp_port())
    ui.start()
    try:
        yield ui
    finally:
        ui.close()


@pytest.fixture(scope="module")
def browser(tmp_path_factory):  # type: ignore[no-untyped-def]
    yield from headless_chromium(tmp_path_factory)


def centroid(app: GcsApp) -> np.ndarray:
    """The team's centroid from its latest telemetry, NED, m."""
    return app.runtime.fleet_table.read(app.clock.now()).p_ned.mean(axis=0)


def open_viewer(browser, ui: WebUi):  # type: ignore[no-untyped-def]
    """A new browser page on the flight's page, and the server's handle of it."""
    before = set(ui.server.get_clients())
    page = browser.new_context(viewport={"width": 1400, "height": 800}).new_page()
    page.goto(page_url(ui.url))
    page.get_by_role("button", name="ABORT: hold, then land").wait_for(timeout=60_000)
    wait_for(lambda: bool(set(ui.server.get_clients()) - before), 10, "the viewer connected")
    new = max(set(ui.server.get_clients()) - before)  # the latest, had the page reconnected
    return page, ui.server.get_clients()[new]


def off_team(client: viser.ClientHandle, app: GcsApp) -> float:
    """How far the point the viewer's camera looks at is from the team, horizontally, m."""
    return float(math.hypot(*(client.camera.look_at - centroid(app))[:2]))


def looks_at_team(client: viser.ClientHandle, app: GcsApp) -> bool:
    """The viewer's camera looks at the team from close enough to see it."""
    c = centroid(app)
    camera = client.camera
    return bool(math.hypot(*(camera.look_at - c)[:2]) < ON_TEAM
                and np.linalg.norm(camera.position - c) < FAR)


def in_view(client: viser.ClientHandle, points: np.ndarray) -> bool:
    """Every point lies inside the viewer's field of view (the narrower, horizontal or
    vertical, with a margin)."""
    camera = client.camera
    forward = camera.look_at - camera.position
    forward /= np.linalg.norm(forward)
    half = 0.45 * camera.fov  # vertical half-angle 0.5 * fov, less a margin
    to = points - camera.position
    angle = np.arccos(np.clip(to @ forward / np.linalg.norm(to, axis=1), -1.0, 1.0))
    return bool(np.all(angle < half))


def camera_text(client: viser.ClientHandle, app: GcsApp) -> str:
    camera = client.camera
    return (f"camera at {np.round(camera.position, 2)} looking at "
            f"{np.round(camera.look_at, 2)}; the team at {np.round(centroid(app), 2)}")


def test_a_viewer_joining_far_from_the_origin_sees_the_team(flight: GcsApp, page_ui: WebUi,
                                                            browser, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """The team is 3 m from the origin when a new viewer opens the page: its camera looks
    at the team (it looked at the origin, whatever the team's place), every vehicle is in
    its field of view and on its screen."""
    away = float(np.hypot(*centroid(flight)[:2]))
    assert away >= AWAY, f"the team is {away:.2f} m from the origin"
    page, client = open_viewer(browser, page_ui)
    try:
        wait_for(lambda: looks_at_team(client, flight), 10, "the camera on the team",
                 lambda: camera_text(client, flight))
        vehicles = flight.runtime.fleet_table.read(flight.clock.now()).p_ned
        assert in_view(client, vehicles), camera_text(client, flight)
        shot = tmp_path / "joined-away.png"
        green, _ = scene_pixels(page, shot)
        print(f"joined {away:.2f} m from the origin: {camera_text(client, flight)}; "
              f"{green} ok-green pixels ({shot})")
        assert green > SCENE_GREEN_MIN, f"{green} vehicle pixels on screen; see {shot}"
    finally:
        page.context.close()


def test_a_page_putting_its_first_view_back_is_framed_again(flight: GcsApp,
                                                            page_ui: WebUi) -> None:
    """A page shows the framing, then puts its own first view back (viser's initial
    camera, looking at the origin), as a loading or reconnecting page does once the
    scene's up direction and initial camera arrive: that is no pan of the viewer's, the
    camera looks at the team again (it stayed on the origin, the follow kept that "pan").
    The page here is a websocket client sending a browser's camera reports."""
    before = set(page_ui.server.get_clients())
    viewer = WireViewer(page_ui.server.get_port())
    try:
        viewer.report_camera((3.0, 3.0, -3.0), (0.0, 0.0, 0.0))  # three.js's default view
        wait_for(lambda: bool(set(page_ui.server.get_clients()) - before), 10,
                 "the viewer connected")
        client = page_ui.server.get_clients()[max(set(page_ui.server.get_clients()) - before)]
        wait_for(lambda: looks_at_team(client, flight), 15, "the framing sent",
                 lambda: camera_text(client, flight))
        camera = client.camera
        viewer.report_camera(tuple(camera.position), tuple(camera.look_at))  # shown
        time.sleep(0.5)  # taken in (viser's thread pool)
        reported: list[np.ndarray] = []

        async def report(camera: viser.CameraHandle) -> None:  # inline: before any move
            reported.append(np.array(camera.look_at))

        client.camera.on_update(report)
        viewer.report_camera((-3.4, -1.0, -2.4), (0.0, 0.0, 0.0))  # the page's first view
        # waits long enough for a busy machine: what is checked is what happens, not when
        wait_for(lambda: any(np.abs(r).max() < 1e-3 for r in reported), 15,
                 "the page's first view reported", lambda: str(reported))
        wait_for(lambda: looks_at_team(client, flight), 15, "the camera on the team again",
                 lambda: camera_text(client, flight))
    finally:
        viewer.close()


def pan_away(page, panned: Callable[[], bool],  # type: ignore[no-untyped-def]
             explain: Callable[[], str]) -> None:
    """Drag the 3-D view with the right button, as a viewer pans it (camera-controls), until
    ``panned``: a drag the browser made before it showed a view the server had just sent
    (the first framing, a centring) is undone by that view, and the viewer drags again."""
    canvases = page.locator("canvas[data-engine^='three.js']")
    boxes = [canvases.nth(k).bounding_box() for k in range(canvases.count())]
    box = max(boxes, key=lambda b: b["width"] * b["height"])
    x, y = box["x"] + 0.1 * box["width"], box["y"] + box["height"] / 2
    for attempt in range(3):
        page.mouse.move(x, y)
        page.mouse.down(button="right")
        page.wait_for_timeout(100)  # held, then dragged and let go, as a hand does: the
        # view moves in its render loop, a few frames a second on a loaded machine, where
        # a drag let go at once went unseen three times in a row (five workers)
        page.mouse.move(x + 0.8 * box["width"], y + 0.1 * box["height"], steps=16)
        page.wait_for_timeout(300)
        page.mouse.up(button="right")
        deadline = time.monotonic() + 3.0
        while time.monotonic() < deadline:
            if panned():
                if attempt:
                    print(f"the view panned at drag {attempt + 1}")
                return
            time.sleep(0.1)
    pytest.fail(f"the view did not pan off the team in 3 drags; {explain()}")


def test_centre_on_team_by_key_and_by_button(flight: GcsApp, page_ui: WebUi,
                                             browser) -> None:  # type: ignore[no-untyped-def]
    """The viewer pans the view off the team (the camera keeps that pan as the team moves,
    the viewer chose it); C, and the View folder's button, bring it back on the team, in
    the browser (its own report of its camera: the server's camera says so as soon as the
    view is sent)."""
    page, client = open_viewer(browser, page_ui)
    reported: list[np.ndarray] = []

    async def report(camera: viser.CameraHandle) -> None:  # what the browser shows
        reported.append(np.array(camera.look_at))

    def browser_on_team() -> bool:
        return bool(reported) and looks_at_team(client, flight) and float(
            math.hypot(*(reported[-1] - centroid(flight))[:2])) < ON_TEAM

    client.camera.on_update(report)
    try:
        wait_for(lambda: looks_at_team(client, flight), 10, "the camera on the team",
                 lambda: camera_text(client, flight))
        for press in (lambda: page.keyboard.press("c"),
                      lambda: page.get_by_role("button", name="Centre on team").click()):
            pan_away(page, lambda: off_team(client, flight) > 1.5,
                     lambda: camera_text(client, flight))
            time.sleep(0.5)  # the page keeps the viewer's pan (re-centred is within ON_TEAM;
            # the follow carries the pan with the moving team, a few cm either way)
            assert off_team(client, flight) > 1.0, camera_text(client, flight)
            press()
            wait_for(browser_on_team, 10, "the browser's camera back on the team",
                     lambda: camera_text(client, flight))
    finally:
        page.context.close()


HOLD_UP_S = RECONNECT_AFTER_S + 1.5
"""How long the machine holds the page up in the test below, s."""


def test_a_page_the_machine_holds_up_keeps_its_socket(flight: GcsApp, page_ui: WebUi,
                                                      browser) -> None:  # type: ignore[no-untyped-def]
    """A busy machine holds the page up for longer than RECONNECT_AFTER_S: all of it (one
    long frame), or only its render loop, which applies what the socket brought (beats
    included) and fell behind. The page does not take either for a silent server (it
    reconnected: a new viewer, the viewer's pan and control gone; seen beside CPU hogs)."""
    page, _ = open_viewer(browser, page_ui)
    try:
        for held, hold_up in (
                ("the page", "s => { const end = performance.now() + 1000 * s; "
                             "while (performance.now() < end); }"),
                ("its render loop", "s => { const raf = window.requestAnimationFrame; "
                                    "const end = performance.now() + 1000 * s; "
                                    "window.requestAnimationFrame = f => { const late = "
                                    "end - performance.now(); return late > 0 ? "
                                    "setTimeout(() => raf(f), late) : raf(f); }; }")):
            wait_for(lambda: is_fresh(page), 15, "the badge fresh",
                     lambda: str(freshness(page)))
            badge, clients = freshness(page), set(page_ui.server.get_clients())
            page.evaluate(hold_up, HOLD_UP_S)
            if held == "its render loop":  # the display's ticks go on, the beats wait
                wait_for(lambda b=badge: freshness(page)["staleAt"] != b["staleAt"],
                         HOLD_UP_S + 5, f"{held} held up: the badge stale")
            # (the whole page held up: the call returned after it; whether the badge shows
            # STALE then is up to the browser: the late beats may be applied first)
            wait_for(lambda: is_fresh(page), HOLD_UP_S + 10, f"{held} fresh again",
                     lambda: str(freshness(page)))
            time.sleep(1.0)  # the display ticks every 0.1 s: a reconnect was forced by now
            assert freshness(page)["reconnects"] == badge["reconnects"], (held, freshness(page))
            assert set(page_ui.server.get_clients()) == clients, f"{held}: connected again"
    finally:
        page.context.close()


STALE_LINE = re.compile(r"no fresh telemetry for [0-9.]+ s: motion frozen ×(\d+)"
                        r" — vehicles 1,2,3,4")


def test_an_event_storm_is_one_line_with_its_count(flight: GcsApp, page_ui: WebUi,
                                                   browser) -> None:  # type: ignore[no-untyped-def]
    """Every vehicle's link cut at once, three times: twelve "no fresh telemetry"
    warnings, shown as one line with their count and the four vehicles; the log's level
    filter hides the information lines, in this viewer only."""
    page, _ = open_viewer(browser, page_ui)
    other, _ = open_viewer(browser, page_ui)
    try:
        for _ in range(3):
            for vid in (1, 2, 3, 4):
                break_vehicle(flight, "cut", vid)
            sim_sleep(flight, 1.0)
            for vid in (1, 2, 3, 4):
                break_vehicle(flight, "restore", vid)
            sim_sleep(flight, 2.0)
        conditions = page.locator("[data-gcs=conditions]")
        # as many as the GCS said (12 here; fewer when a loaded machine let the vehicles
        # drop to HOLD during a cut, which says so in a line of its own, or let a cut
        # last into the landing rule, whose "no fresh telemetry ...: landing the team" is
        # a line of its own too)
        said = sum(1 for e in flight.loop.events()
                   if "no fresh telemetry" in e.text and "motion frozen" in e.text)
        assert said >= 4, said

        def stale_lines() -> list[str]:
            return [line for line in conditions.inner_text().splitlines()
                    if "no fresh telemetry" in line and "motion frozen" in line]

        def shown_count() -> int | None:  # the storm's own line (another may say ×12 too)
            found = [STALE_LINE.search(line) for line in stale_lines()]
            return int(found[0].group(1)) if len(found) == 1 and found[0] else None

        wait_for(lambda: shown_count() == said, 10, f"the storm's count ×{said}",
                 lambda: conditions.inner_text())
        stale = stale_lines()
        print(f"the storm on the page: {stale}")
        assert len(stale) == 1 and STALE_LINE.search(stale[0]), stale

        # the log is a panel of its own, drawn apart from the conditions (seen empty at
        # this point on a loaded machine)
        log = page.locator("[data-gcs=event-log] [data-level=info]")
        wait_for(lambda: log.count() > 0 and log.first.is_visible(), 10,
                 "the information lines in the log")
        page.get_by_label("errors", exact=True).check()
        wait_for(lambda: not log.first.is_visible(), 5, "the information lines hidden")
        assert other.locator("[data-gcs=event-log] [data-level=info]").first.is_visible()
        page.get_by_label("all", exact=True).check()
        wait_for(lambda: log.first.is_visible(), 5, "the information lines shown again")
    finally:
        page.context.close()
        other.context.close()
