"""The live page in a real browser against a real ``gcs demo`` (simulator, GCS, page).

Headless Chromium (Debian's /usr/bin/chromium) is driven by Playwright. The
vehicles' motion is read from the simulator's ground truth over zenoh by a
second, independent zenoh session, so a test passes only if the real
simulated vehicles moved. What each browser received over its websocket is
decoded too (``web.wireviewer.SceneRecord``): the scene it holds and how many
updates a second reach it. The tests share one demo and run in file order:
take control and lift from the page, a viewer whose connection stops while the team
climbs (its badge says STALE, then it reconnects), fly from the page, then a second
viewer, then the abort (from the keyboard, and
the always-visible button at a small window with the panels collapsed), then
Ctrl-C, then the button of a page whose server is gone. The README's command runs
them alone after the rest of the suite (marker ``live_demo``): beside it, the page
answered too late and the vehicles held mid-test (and the run was no shorter: the
machine's two cores were busy throughout). They run as the operator's foreground job
(:func:`foreground`). On several workers the file stays on one of them, in this order
(its ``xdist_group``, with ``--dist loadgroup``).
Screenshots go to the pytest temporary
directory (the path is printed; ``-s`` shows it).
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
import viser

from gcs.app import free_tcp_port
from gcs.testing import team_key
from gcs.transport import ZenohSettings, open_session
from gcs.wire import SimTruth, Unsealer, keys
from tests.support.colours import hue_apart, hue_saturation_value
from tests.support.paths import ROOT
from web import palette
from web._browser_script import ABORT_ANSWERS, RECONNECT_AFTER_S, STALE_AFTER_S
from web.wireviewer import SceneRecord

# One process runs the whole file in order: the tests share one demo, and the last ones stop
# it; the README runs them alone (live_demo), since the demo flies on the wall clock.
pytestmark = [pytest.mark.xdist_group("browser"), pytest.mark.live_demo]

CHROMIUM = Path("/usr/bin/chromium")
VEHICLES = "/team/vehicles"
SCENE_GREEN_MIN = 500
SCENE_MAGENTA_MIN = 50
"""Pixels of the ok vehicles' green and of the payload's magenta the start view must show
(measured: see the printed counts; with either hidden, the count is 0)."""
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update",
                 "--disable-sync"]

if not CHROMIUM.exists():
    pytest.skip("browser tests need Debian's chromium at /usr/bin/chromium "
                "(apt-get install -y chromium)", allow_module_level=True)
sync_api = pytest.importorskip("playwright.sync_api",
                               reason="browser tests need playwright (pip install playwright)")


FOREGROUND_NICE = -5
"""The live demo's priority where the test may raise it (root): above other work's."""


@pytest.fixture(scope="module", autouse=True)
def foreground() -> Iterator[None]:
    """The demo, its simulator, Playwright and the browser as the operator's foreground
    job, ahead of other work on the machine (CPU hogs): this thread runs at nice
    :data:`FOREGROUND_NICE` for the module, as root, and what it starts inherits that
    (chromium sets its own threads' priorities back to 0). Beside two CPU hogs at the same
    priority the demo's setpoints came late enough for every vehicle to hold mid-test in
    some runs; what the tests check is the page and its controls, not the machine's load.
    Elsewhere (not root) nothing changes."""
    if os.geteuid() != 0:
        yield
        return
    before = os.getpriority(os.PRIO_PROCESS, 0)
    os.setpriority(os.PRIO_PROCESS, 0, FOREGROUND_NICE)  # Linux: this thread, and children
    try:
        yield
    finally:
        os.setpriority(os.PRIO_PROCESS, 0, before)


class Demo:
    """A running ``gcs demo`` subprocess and a zenoh reader of the sim's truth."""

    def __init__(self) -> None:
        self.port = free_tcp_port()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "gcs", "demo", "--port", str(self.port),
             "--no-gamepad"],
            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            env={**os.environ, "PYTHONUNBUFFERED": "1"})
        self.lines: list[str] = []
        self.err: list[str] = []
        threading.Thread(target=self._pump, args=(self.proc.stderr, self.err),
                         daemon=True).start()
        self.url = ""
        self.endpoint = ""
        deadline = time.monotonic() + 120.0
        assert self.proc.stdout is not None
        while not self.url:
            line = self.proc.stdout.readline()
            if not line:
                raise RuntimeError(f"gcs demo exited: {' | '.join(self.err[-8:])}")
            self.lines.append(line)
            if m := re.search(r"zenoh listen (tcp/\S+),", line):
                self.endpoint = m.group(1)
            if m := re.search(r"GCS page: (http://\S+)", line):
                self.url = m.group(1)
            if time.monotonic() > deadline:
                raise RuntimeError("gcs demo did not print its page address in 120 s")
        threading.Thread(target=self._pump, args=(self.proc.stdout, self.lines),
                         daemon=True).start()
        self.session = open_session(ZenohSettings(mode="peer", connect=(self.endpoint,)))
        self.truth: SimTruth | None = None
        self.first: SimTruth | None = None  # the team's heading is measured from here
        topic = keys.sim("default", "truth")
        unseal = Unsealer(team_key(), topic).open  # the simulator seals it with the team key

        def take(sample) -> None:  # type: ignore[no-untyped-def]
            self.truth = SimTruth.from_bytes(unseal(bytes(sample.payload.to_bytes())))
            self.first = self.first or self.truth  # on the ground, before any turn

        self._sub = self.session.declare_subscriber(topic, take)

    @staticmethod
    def _pump(stream, sink: list[str]) -> None:  # type: ignore[no-untyped-def]
        for line in stream:
            sink.append(line)

    def sample(self, after: float = -1.0) -> SimTruth:
        """The latest truth sample, waiting for one later than sim time ``after``.

        Truth is latest-wins (dropped under load), so a reader waits for a fresh one
        rather than assume one arrived. The wait allows the demo's simulator a tenth of
        real time, as beside CPU hogs, plus 10 s.
        """
        ahead = after - self.truth.t if self.truth is not None else 0.0
        deadline = time.monotonic() + 10.0 + 10.0 * max(ahead, 0.0)
        while self.truth is None or self.truth.t <= after:
            assert time.monotonic() < deadline, f"no sim truth after t = {after} s on zenoh"
            time.sleep(0.02)
        return self.truth

    def velocity(self, window: float = 0.4) -> np.ndarray:
        """The team's true horizontal velocity over about ``window`` s of sim time, m/s,
        along its own axes (forward, right): the axes the sticks command. Once the team
        has turned, "right" is no longer east."""
        first = self.sample()
        last = self.sample(after=first.t + window)
        moved = np.asarray(last.vehicle_p_ned)[:, :2] - np.asarray(first.vehicle_p_ned)[:, :2]
        north, east = moved.mean(axis=0) / (last.t - first.t)
        c, s = np.cos(self.heading(last)), np.sin(self.heading(last))
        return np.array([c * north + s * east, -s * north + c * east])

    def heading(self, truth: SimTruth) -> float:
        """How far the team has turned since its first truth sample, rad, clockwise from
        above (its bearings from the centroid do not change as it scales)."""
        assert self.first is not None, "no truth sample yet"
        turned = np.angle(np.exp(1j * (_bearings(truth) - _bearings(self.first))))
        return float(turned.mean())

    def spin(self, window: float = 0.4) -> float:
        """The team's true rotation rate about its centroid, rad/s, clockwise from above."""
        first = self.sample()
        last = self.sample(after=first.t + window)
        turned = np.angle(np.exp(1j * (_bearings(last) - _bearings(first))))  # wrapped
        return float(turned.mean()) / (last.t - first.t)

    def close(self) -> None:
        """Stop the demo like Ctrl-C (so it stops its simulator too); kill it if it hangs."""
        self._sub.undeclare()
        self.session.close()
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)


def _bearings(truth: SimTruth) -> np.ndarray:
    """Each vehicle's bearing from the team's centroid (NED: clockwise from above), rad."""
    p = np.asarray(truth.vehicle_p_ned)[:, :2]
    r = p - p.mean(axis=0)
    return np.arctan2(r[:, 1], r[:, 0])


@pytest.fixture(scope="module")
def demo() -> Iterator[Demo]:
    d = Demo()
    try:
        yield d
    finally:
        d.close()


def unprivileged_chromium(directory: Path) -> Path:
    """Debian's chromium as an ordinary user's browser: without the right to raise priority.

    CI runs as root, and chromium started by root raises its GPU thread to nice
    -8 (an ordinary user's chromium cannot). On two cores its software WebGL then
    starves the demo under test: the GCS fell 0.5 s behind and every vehicle
    held, which a real operator's browser would not do. ``setpriv`` drops the
    capability for chromium alone; without ``setpriv`` chromium runs as is.
    """
    setpriv = shutil.which("setpriv")
    if os.geteuid() != 0 or setpriv is None:
        return CHROMIUM
    wrapper = directory / "chromium"
    wrapper.write_text("#!/bin/sh\n"
                       f"exec {setpriv} --inh-caps=-sys_nice --bounding-set=-sys_nice "
                       f'{CHROMIUM} "$@"\n')
    wrapper.chmod(0o755)
    return wrapper


SOFTWARE_DPR = 0.5
"""The 3D view's pixel ratio in pages that watch a flight faster than real time (viser's
``fixedDpr``): headless chromium draws WebGL on the CPU (SwiftShader), at a cost that
grows with the pixels. A 1400x800 page at full ratio drew a moving sphere at 6 frames/s
for 1.5 CPU-s/s; at 0.5, at its full 10 Hz for 0.65. The live demo's pages keep the full
ratio: a user's page, whose colours :func:`scene_pixels` counts."""


def page_url(url: str) -> str:
    """``url`` of a live page, for a test browser: the 3D view at :data:`SOFTWARE_DPR`."""
    return f"{url}{'&' if '?' in url else '?'}fixedDpr={SOFTWARE_DPR}"


def headless_chromium(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    """Headless Chromium, as an ordinary user's browser, until the generator is closed (the
    body of a module's ``browser`` fixture)."""
    executable = unprivileged_chromium(tmp_path_factory.mktemp("chromium"))
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=str(executable), headless=True, args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture(scope="module")
def browser(tmp_path_factory):  # type: ignore[no-untyped-def]
    yield from headless_chromium(tmp_path_factory)


WIRES: dict[int, SceneRecord] = {}
"""What each page (by ``id``) received over its websocket, decoded."""
SENT: dict[int, list[tuple[float, bytes]]] = {}
"""What each page (by ``id``) sent over its websocket: (time, raw msgpack frame)."""


def open_page(browser, demo: Demo, url: str = ""):  # type: ignore[no-untyped-def]
    """A new browser page on the demo's page (or on ``url``, a way to it)."""
    page = browser.new_context(viewport={"width": 1400, "height": 800}).new_page()
    record = WIRES[id(page)] = SceneRecord()
    sent = SENT[id(page)] = []

    def on_websocket(ws) -> None:  # type: ignore[no-untyped-def]
        def on_frame(payload: bytes | str) -> None:
            if isinstance(payload, bytes):
                record.take(payload, time.monotonic())
        ws.on("framereceived", on_frame)
        ws.on("framesent", lambda payload: sent.append(
            (time.monotonic(), payload if isinstance(payload, bytes) else payload.encode())))

    page.on("websocket", on_websocket)
    page.goto(url or demo.url)
    page.get_by_role("button", name="ABORT: hold, then land").wait_for(timeout=30_000)
    return page


def wire(page) -> SceneRecord:  # type: ignore[no-untyped-def]
    """The scene as ``page`` received it (Playwright delivers frames during its own calls)."""
    page.evaluate("0")
    return WIRES[id(page)]


@pytest.fixture(scope="module")
def screens(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Where the tests' screenshots go (printed, to look at after a run)."""
    path = tmp_path_factory.mktemp("screens")
    print(f"browser screenshots: {path}")
    return path


@pytest.fixture(scope="module")
def pilot(browser, demo: Demo):  # type: ignore[no-untyped-def]
    return open_page(browser, demo)


@pytest.fixture(scope="module")
def viewer(browser, demo: Demo):  # type: ignore[no-untyped-def]
    """A second browser, opened when the second-viewer test needs it."""
    return open_page(browser, demo)


def text(page, what: str) -> str:  # type: ignore[no-untyped-def]
    return page.locator(f"[data-gcs={what}]").inner_text()


def wait_for(check: Callable[[], bool], timeout: float, what: str,
             explain: Callable[[], str] = lambda: "") -> None:
    """Poll ``check``; on timeout fail naming ``what`` and what ``explain`` says."""
    deadline = time.monotonic() + timeout
    while not check():
        assert time.monotonic() < deadline, f"timed out waiting for {what}; {explain()}"
        time.sleep(0.1)


def banner(page) -> str:  # type: ignore[no-untyped-def]
    """The viewer's control banner (first line of the panel)."""
    return page.get_by_text(re.compile(r"^(You hold control|View only)")).first.inner_text()


def steer(demo: Demo, press: Callable[[], None], release: Callable[[], None],
          hold: float = 2.0, held: Callable[[], None] = lambda: None,
          motion: Callable[[], np.ndarray | float] | None = None) -> np.ndarray:
    """Change of the team's true motion (``motion``: velocity, m/s) while an input is held
    for ``hold`` s of sim time (the demo's simulator falls behind the wall clock on a
    loaded machine: 2 wall seconds once changed the velocity by 0.02 m/s, not 0.1).

    The paper's gains accelerate and brake gently (velocity gain c1 = 0.17/s), so
    the team still drifts from earlier inputs: compare velocities, not positions.
    ``held`` runs while the input is still held (checks of the operator command).
    """
    measure = motion or demo.velocity
    before = measure()
    press()
    demo.sample(after=demo.sample().t + hold)
    after = measure()
    try:
        held()
    finally:
        release()
    return np.asarray(after) - np.asarray(before)


def commanded(page, stick: str, check: Callable[[float], bool],  # type: ignore[no-untyped-def]
              what: str) -> Callable[[], None]:
    """A check that the page shows the loop commanding ``stick`` as ``check`` wants."""
    def run() -> None:
        wait_for(lambda: check(float(operator(page)[stick])), 3, what,
                 lambda: f"command {text(page, 'operator')}")
        assert str(operator(page)["source"]).startswith("browser#")
    return run


def situation(page, demo: Demo) -> str:  # type: ignore[no-untyped-def]
    """What the page and the demo said, for a failure message."""
    rows = " | ".join(page.locator(f"[data-gcs=vehicle-{vid}]").inner_text().replace("\n", " ")
                      for vid in (1, 2, 3, 4))
    centre = np.asarray(demo.truth.vehicle_p_ned).mean(axis=0) if demo.truth else None
    notices = " | ".join(page.locator(".mantine-Notification-root").all_inner_texts())
    return (f"phase {text(page, 'phase')}; team at {centre} m (NED); notices [{notices}]; "
            f"command {text(page, 'operator')}; "
            f"vehicles {rows}; events {text(page, 'events')[-600:]}; "
            f"demo said {''.join(demo.lines[-6:] + demo.err[-6:])[-800:]}")


def operator(page) -> dict[str, float | str]:  # type: ignore[no-untyped-def]
    """The operator command shown on the page (the loop's snapshot)."""
    t = text(page, "operator")
    values: dict[str, float | str] = {k: float(v) for k, v in
                                      re.findall(r"(fwd|right|rot) ([+-]?[0-9.]+)", t)}
    values["scale"] = float(re.search(r"→ ([0-9.]+) ·", t).group(1))  # type: ignore[union-attr]
    values["target"] = float(re.search(r"→ ([0-9.]+) m", t).group(1))  # type: ignore[union-attr]
    values["source"] = t.rsplit("from ", 1)[1]
    return values


def near_hue(hue: np.ndarray, colour: tuple[int, int, int] | np.ndarray,
             within: float) -> np.ndarray:
    """Where ``hue`` is within ``within`` degrees of ``colour``'s hue."""
    return hue_apart(hue, colour) <= within


GIZMO_PX = 120
"""The axes gizmo (pure red, green and blue) sits in this square at the view's bottom left."""


def scene_pixels(page, save: Path) -> tuple[int, int]:  # type: ignore[no-untyped-def]
    """Pixels of the 3-D view in an ok vehicle's green and in the payload's magenta.

    By hue and saturation, whatever the lighting's shade: no other colour of the
    scene comes near these hues (``web/palette.py``, the rule tested in
    tests/web/test_frame.py), nor do the page's notifications or the red abort button.
    The screenshot is saved to ``save``.
    """
    import imageio.v3 as iio  # a viser dependency

    canvases = page.locator("canvas[data-engine^='three.js']")
    boxes = [canvases.nth(k).bounding_box() for k in range(canvases.count())]
    biggest = max(range(len(boxes)), key=lambda k: boxes[k]["width"] * boxes[k]["height"])
    png = canvases.nth(biggest).screenshot(path=str(save))
    rgb = np.asarray(iio.imread(png, extension=".png"))[..., :3].copy()
    rgb[-GIZMO_PX:, :GIZMO_PX] = 255
    hue, saturation, value = hue_saturation_value(rgb)
    green = near_hue(hue, palette.OK, 22.0) & (saturation >= 0.3) & (value >= 0.15)
    magenta = near_hue(hue, palette.PAYLOAD, 22.0) & (saturation >= 0.5) & (value >= 0.12)
    return int(green.sum()), int(magenta.sum())


def test_page_shows_the_team_and_the_payload(pilot, demo: Demo, screens: Path) -> None:
    wait_for(lambda: text(pilot, "phase") == "ready", 30, "phase ready")
    for vid in (1, 2, 3, 4):
        row = pilot.locator(f"[data-gcs=vehicle-{vid}]").inner_text()
        assert "DISARMED" in row and "ok" in row, row
    assert "(simulator)" in text(pilot, "payload")

    # what the browser received: NED shown right way up (up is -z), every vehicle and the
    # payload visible, in their colours, where the simulator has them
    truth = demo.sample()
    scene = wire(pilot)
    root = viser.transforms.SO3(np.array(scene.wait_for("")["wxyz"])).as_matrix()
    np.testing.assert_allclose(root @ [0.0, 0.0, -1.0], [0.0, 1.0, 0.0], atol=1e-6)
    vehicles = scene.wait_for("/team/vehicles")
    order = [list(truth.ids).index(vid) for vid in (1, 2, 3, 4)]
    assert vehicles["visible"]
    np.testing.assert_allclose(vehicles["batched_positions"].reshape(-1, 3),
                               np.asarray(truth.vehicle_p_ned)[order], atol=0.1)
    np.testing.assert_array_equal(vehicles["batched_scales"], 1.0)
    assert (vehicles["batched_colors"].reshape(-1, 3) == palette.OK).all()
    payload = scene.wait_for("/team/payload")
    assert payload["visible"] and tuple(payload["color"]) == tuple(palette.PAYLOAD)
    np.testing.assert_allclose(payload["position"], truth.payload_p_ned, atol=0.1)

    # ... and what it drew
    shot = screens / "ready-scene.png"
    green, magenta = scene_pixels(pilot, shot)
    print(f"3-D view at ready: {green} ok-green, {magenta} payload-magenta pixels ({shot})")
    assert green > SCENE_GREEN_MIN and magenta > SCENE_MAGENTA_MIN, (
        f"3-D view: {green} vehicle, {magenta} payload pixels; see {shot}")
    assert "nobody" in text(pilot, "control")
    assert banner(pilot).startswith("View only")
    assert pilot.get_by_role("button", name="arm", exact=True).is_disabled()


class Relay:
    """A TCP relay from a page to the demo that can stop delivering, both ways.

    A stopped connection stays open and carries nothing: a half-open websocket, the
    page's view frozen while the GCS and every other viewer carry on. Connections
    opened after :meth:`stop` flow (the page's reconnect). Bytes the relay already
    read when stopped are held, not lost, until :meth:`resume`.
    """

    def __init__(self, port: int) -> None:
        self._port = port
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.url = f"http://127.0.0.1:{self._listener.getsockname()[1]}"
        self._pairs: list[tuple[socket.socket, socket.socket, threading.Event]] = []
        self._lock = threading.Lock()
        threading.Thread(target=self._accept, daemon=True, name="relay").start()

    def _accept(self) -> None:
        while True:
            try:
                near, _ = self._listener.accept()
            except OSError:
                return  # closed
            far = socket.create_connection(("127.0.0.1", self._port))
            flowing = threading.Event()
            flowing.set()
            for s in (near, far):
                s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            with self._lock:
                self._pairs.append((near, far, flowing))
            for src, dst in ((near, far), (far, near)):
                threading.Thread(target=self._pump, args=(src, dst, flowing), daemon=True,
                                 name="relay-pump").start()

    @staticmethod
    def _pump(src: socket.socket, dst: socket.socket, flowing: threading.Event) -> None:
        try:
            while data := src.recv(65536):
                flowing.wait()
                dst.sendall(data)
            dst.shutdown(socket.SHUT_WR)
        except OSError:
            pass  # closed

    @property
    def connections(self) -> int:
        """Connections opened through the relay so far (page loads and websockets)."""
        with self._lock:
            return len(self._pairs)

    def stop(self) -> float:
        """Stop every connection open now; return when (wall clock, s)."""
        with self._lock:
            for _, _, flowing in self._pairs:
                flowing.clear()
        return time.time()

    def resume(self) -> float:
        """Let every connection flow again; return when (wall clock, s)."""
        with self._lock:
            for _, _, flowing in self._pairs:
                flowing.set()
        return time.time()

    def close(self) -> None:
        self._listener.close()
        with self._lock:
            for near, far, flowing in self._pairs:
                flowing.set()
                near.close()
                far.close()


def freshness(page) -> dict[str, str]:  # type: ignore[no-untyped-def]
    """The page's freshness badge: its text, state ("fresh", "stale"), when it last turned
    stale and fresh (the page's wall clock, ms), its forced reconnects, its colour."""
    return page.locator("[data-gcs=freshness]").evaluate(
        """b => ({text: b.textContent, state: b.dataset.gcsState || "",
                  staleAt: b.dataset.gcsStaleAt || "", freshAt: b.dataset.gcsFreshAt || "",
                  reconnects: b.dataset.gcsReconnects || "0", time: b.dataset.gcsTime || "",
                  background: getComputedStyle(b).backgroundColor})""")


STALE_SHOWN = "() => document.querySelector('[data-gcs=freshness]').dataset.gcsState === 'stale'"
"""True once the page's badge says STALE (polled in the page, so the test sees it at once)."""


def is_fresh(page) -> bool:  # type: ignore[no-untyped-def]
    badge = freshness(page)
    return badge["state"] == "fresh" and re.fullmatch(r"data \d+\.\d s old", badge["text"]) \
        is not None


def press_phase(page, button: str, phase: str, demo: Demo,  # type: ignore[no-untyped-def]
                timeout: float = 40.0) -> None:
    """Press a phase button and wait for the page to show ``phase``."""
    clicked = time.monotonic()
    page.get_by_role("button", name=button, exact=True).click()

    def explain() -> str:
        page.evaluate("0")  # Playwright delivers websocket events during its own calls
        frames = [f"+{t - clicked:.2f} s {len(f)} B" for t, f in SENT[id(page)]
                  if t >= clicked and button.encode() in f]
        return f"frames naming {button!r} sent since the click: {frames}; " + situation(page, demo)

    wait_for(lambda: text(page, "phase") == phase, timeout, f"phase {phase}", explain)


def test_the_pilot_takes_control_and_lifts_with_the_buttons(pilot, demo: Demo) -> None:
    """The pilot takes control, arms, takes off, lifts, sets down while lifting, and lifts
    again: the test ends as the team climbs (about 21 s at speed 1), which the next one
    (a viewer whose connection stops) spends."""
    pilot.get_by_role("button", name="Take control").click()
    wait_for(lambda: banner(pilot) == "You hold control.", 10, "control taken")
    # the script's channel exists for the holder and is never shown (the sticks and keys
    # below travel through it)
    field = pilot.locator("label", has_text=re.compile(r"^browser input$"))
    wait_for(lambda: field.count() == 1 and not field.is_visible(), 5,
             "the browser input field present and hidden", lambda: f"{field.count()} fields")
    for button, phase in (("arm", "armed"), ("take off", "hover"), ("lift", "lifting")):
        press_phase(pilot, button, phase, demo)
    # set down while lifting: the altitude target drops back, the team is in hover again
    lifted = float(operator(pilot)["target"])
    press_phase(pilot, "set down", "setting down", demo, timeout=10)
    # the phase shows with its event at once, the operator line with the next tick
    wait_for(lambda: float(operator(pilot)["target"]) < lifted - 1.0, 5,
             "the altitude target back down", lambda: text(pilot, "operator"))
    wait_for(lambda: text(pilot, "phase") == "hover", 30, "hover after set down",
             lambda: situation(pilot, demo))
    press_phase(pilot, "lift", "lifting", demo)


def test_a_viewer_that_stops_receiving_says_stale_and_reconnects(browser, pilot,
                                                                 demo: Demo) -> None:
    """A viewer reaches the demo through a relay that stops delivering (its websocket stays
    open, nothing arrives): its badge turns red, STALE, within a second of the stop, while
    the pilot's page stays fresh; updates flowing again make it fresh; stopped for good,
    the page opens a fresh websocket by itself and is fresh again."""
    relay = Relay(int(demo.url.rsplit(":", 1)[1]))
    page = open_page(browser, demo, url=relay.url)
    sockets: list[str] = []
    page.on("websocket", lambda ws: sockets.append(ws.url))
    try:
        wait_for(lambda: is_fresh(page), 15, "the badge fresh", lambda: str(freshness(page)))
        ok = freshness(page)
        gcs_time = float(ok["time"])
        before = ok["reconnects"]  # a page that loaded slowly (two test workers, a loaded
        # machine) may have reconnected once already: what the relay does counts from here
        assert ok["background"] != "rgb(201, 42, 42)", ok

        # the relay stops: STALE, in red, about a second after the last beat, which came
        # before the stop (slack: the page applies what it receives in its render loop)
        time.sleep(0.5)
        assert is_fresh(page), freshness(page)
        stopped = relay.stop()
        page.wait_for_function(STALE_SHOWN, polling=20, timeout=5_000)
        stale = freshness(page)
        resumed = relay.resume()  # at once: well before the page gives up on its socket
        after = float(stale["staleAt"]) / 1e3 - stopped
        print(f"STALE shown {after:.2f} s after the stop: {stale['text']!r}")
        assert 0.0 < after <= STALE_AFTER_S + 0.3, f"STALE {after:.2f} s after the stop"
        assert re.fullmatch(r"STALE — no update for \d\.\d s", stale["text"]), stale
        assert stale["background"] == "rgb(201, 42, 42)", stale
        assert is_fresh(pilot), f"the pilot's page: {freshness(pilot)}"  # the GCS goes on

        # updates flowed again at once: fresh, over the same socket
        assert resumed - stopped < RECONNECT_AFTER_S - 1.0, resumed - stopped
        wait_for(lambda: is_fresh(page), 5, "fresh again", lambda: str(freshness(page)))
        back = float(freshness(page)["freshAt"]) / 1e3 - resumed
        print(f"fresh {back:.2f} s after the relay resumed")
        assert float(freshness(page)["time"]) > gcs_time
        assert freshness(page)["reconnects"] == before and not sockets, (
            freshness(page), sockets)

        # stopped for good: after RECONNECT_AFTER_S the page reconnects, over a new socket
        stopped = relay.stop()
        wait_for(lambda: freshness(page)["reconnects"] != before, RECONNECT_AFTER_S + 3,
                 "a forced reconnect", lambda: str(freshness(page)))
        wait_for(lambda: is_fresh(page), 20, "fresh after the reconnect",
                 lambda: f"{freshness(page)}; sockets {sockets}")
        back = float(freshness(page)["freshAt"]) / 1e3 - stopped
        print(f"stopped for good: reconnected, fresh {back:.2f} s after the stop "
              f"({freshness(page)['reconnects']} forced reconnect(s), new sockets {sockets})")
        assert len(sockets) >= 1, sockets
        # it waited for the reconnect timeout, which runs from the last beat the page had:
        # that came before the stop (by up to a beat period, more on a loaded machine:
        # 2.997 s was seen with two CPU hogs), never a reconnect at once
        assert back > RECONNECT_AFTER_S - STALE_AFTER_S, back
    finally:
        page.context.close()
        relay.close()


def test_the_pilot_flies_the_team_with_keys_and_sticks(pilot, demo: Demo,
                                                       screens: Path) -> None:
    # about 21 s of climb at speed 1 since the last test's lift: the pickup band at
    # 0.02 m/s, then 0.1 m/s
    wait_for(lambda: text(pilot, "phase") == "formation", 90, "phase formation",
             lambda: situation(pilot, demo))

    # hotkey: hold W, the loop commands full forward and the real team speeds up northwards
    keyboard = pilot.keyboard
    dv = steer(demo, lambda: keyboard.down("w"), lambda: keyboard.up("w"),
               held=commanded(pilot, "fwd", lambda v: v > 0.9, "fwd > 0.9 while W is held"))
    assert dv[0] > 0.1, (
        f"velocity change {dv} m/s (forward, right) with W; expected forward; "
        f"{situation(pilot, demo)}")
    wait_for(lambda: operator(pilot)["fwd"] == 0.0, 5, "sticks centred after W is released")
    assert str(operator(pilot)["source"]).startswith("browser#")

    # guidance off: shown, a held S (back: south, against the drift W left, away from the
    # geofence) commands nothing and the team does not speed up; switched on again with S
    # still held, S flies (the key was sent all along: a focused checkbox takes no keys)
    guidance = pilot.get_by_label("guidance on")
    guidance.click()
    wait_for(lambda: "guidance off" in text(pilot, "operator"), 5, "guidance off shown")
    before = demo.velocity()
    keyboard.down("s")
    try:
        time.sleep(2.0)
        after = demo.velocity()
        assert operator(pilot)["fwd"] == 0.0, text(pilot, "operator")
        guidance.click()
        wait_for(lambda: "guidance on" in text(pilot, "operator"), 5, "guidance on shown")
        commanded(pilot, "fwd", lambda v: v < -0.9, "fwd < -0.9: S held, guidance on")()
        # and brakes the drift W left (the geofence is 4 m from the start) until the team
        # moves north no more: on a loaded machine a fixed 1.5 s left it drifting into the
        # fence's slowdown, which then spoiled the sticks' steps below
        wait_for(lambda: demo.velocity()[0] < 0.05, 10, "the drift north braked by S",
                 lambda: situation(pilot, demo))
    finally:
        keyboard.up("s")
    print(f"guidance off, S held 2 s: speed {np.linalg.norm(before):.3f} -> "
          f"{np.linalg.norm(after):.3f} m/s")
    assert np.linalg.norm(after) <= np.linalg.norm(before) + 0.03, (
        f"guidance off, S held 2 s: velocity {before} -> {after} m/s; "
        f"{situation(pilot, demo)}")
    wait_for(lambda: operator(pilot)["fwd"] == 0.0, 5, "sticks centred after S")

    # hotkey: hold E, the loop commands clockwise rotation and the real team turns clockwise
    dw = steer(demo, lambda: keyboard.down("e"), lambda: keyboard.up("e"), motion=demo.spin,
               held=commanded(pilot, "rot", lambda v: v > 0.9, "rot > 0.9 while E is held"))
    print(f"rotation rate change with E held 2 s: {dw:.3f} rad/s")
    assert dw > 0.02, f"rotation rate change {dw} rad/s with E; {situation(pilot, demo)}"
    wait_for(lambda: operator(pilot)["rot"] == 0.0, 5, "rotation centred after E is released")

    # virtual stick: drag the pad to the left and hold (west), then right (brake)
    pad = pilot.locator("[data-gcs-pad=move]").bounding_box()
    cx, cy = pad["x"] + pad["width"] / 2, pad["y"] + pad["height"] / 2
    mouse = pilot.mouse

    def drag(dx: float) -> None:
        mouse.move(cx, cy)
        mouse.down()
        mouse.move(cx + dx * pad["width"] / 2, cy, steps=4)

    print(f"the team has turned {demo.heading(demo.sample()):.2f} rad: the pad's left is "
          "along its own axes")
    dv = steer(demo, lambda: drag(-1.0), mouse.up,
               held=commanded(pilot, "right", lambda v: v < -0.9, "right < -0.9, pad left"))
    assert dv[1] < -0.1, (
        f"velocity change {dv} m/s (forward, right) with the pad left; expected left; "
        f"{situation(pilot, demo)}")
    wait_for(lambda: operator(pilot)["right"] == 0.0, 5, "the pad springs back")
    dv = steer(demo, lambda: drag(1.0), mouse.up,
               held=commanded(pilot, "right", lambda v: v > 0.9, "right > 0.9, pad right"))
    assert dv[1] > 0.1, (
        f"velocity change {dv} m/s (forward, right) with the pad right; expected right; "
        f"{situation(pilot, demo)}")

    # the rotation bar: dragged left is counter-clockwise, and springs back
    bar = pilot.locator("[data-gcs-pad=turn]").bounding_box()
    bx, by = bar["x"] + bar["width"] / 2, bar["y"] + bar["height"] / 2
    mouse.move(bx, by)
    mouse.down()
    mouse.move(bx - 0.6 * bar["width"], by, steps=4)  # past the end: full deflection
    try:
        commanded(pilot, "rot", lambda v: v < -0.9, "rot < -0.9, bar left")()
    finally:
        mouse.up()
    wait_for(lambda: operator(pilot)["rot"] == 0.0, 5, "the bar springs back")

    # step keys: scale and altitude targets
    before = operator(pilot)
    keyboard.press("+")
    keyboard.press("PageUp")
    wait_for(lambda: operator(pilot)["scale"] == pytest.approx(float(before["scale"]) + 0.05),
             5, "scale target one step up")
    wait_for(lambda: operator(pilot)["target"] == pytest.approx(float(before["target"]) + 0.1),
             5, "altitude target one step up")
    keyboard.press("-")
    wait_for(lambda: operator(pilot)["scale"] == pytest.approx(before["scale"]), 5,
             "scale target back")


    # the rate this browser receives the team's frames at (not what the server meant to
    # send), and its vehicles' moves among them
    scene = wire(pilot)
    start, frames, moves = time.monotonic(), scene.updates("/team"), scene.updates(VEHICLES)
    pilot.wait_for_timeout(4000)  # Playwright delivers the frames while it waits
    scene = wire(pilot)
    elapsed = time.monotonic() - start
    rate = (scene.updates("/team") - frames) / elapsed
    moved = (scene.updates(VEHICLES) - moves) / elapsed
    print(f"received by the browser: {rate:.1f} scene updates/s, {moved:.1f} with the "
          f"vehicles moved (the page drew {text(pilot, 'ui-rate')}/s)")
    # Behaviour, not speed: the page keeps streaming the moving team to this browser (the
    # 20 Hz target is measured by bench/ui_update.py; a loaded CI machine may fall short).
    assert rate >= 10.0 and moved > 0.0, \
        f"the browser received {rate:.1f} scene updates a second ({moved:.1f} with moves)"

    # the vehicles' tables fit their panel: each last column without scrolling sideways
    # (measured in one go: the tables are rebuilt with every tick)
    fit = pilot.evaluate("""() => {
        const box = document.querySelector("[data-gcs=vehicles]");
        const last = [...box.querySelectorAll("table tr:first-child th:last-child")];
        return {headers: last.map(h => h.textContent),
                overflow: box.scrollWidth - box.clientWidth,
                right: Math.max(...last.map(h => h.getBoundingClientRect().right)),
                panel: box.getBoundingClientRect().right};
    }""")
    assert (fit["headers"] == ["rope N (sim)", "position source"] and fit["overflow"] <= 1
            and fit["right"] <= fit["panel"]), f"the vehicles' tables do not fit: {fit}"

    pilot.get_by_role("tab", name="Plots").click()
    assert pilot.get_by_text("distances (m)").is_visible()
    pilot.get_by_role("tab", name="Status").click()
    shot = screens / "page-flying.png"
    pilot.screenshot(path=str(shot))
    print(f"page while flying: {shot}")
    assert shot.stat().st_size > 50_000
    if os.environ.get("GCS_SAVE_SCREENSHOT"):  # refresh the README's picture
        notices = pilot.locator(".mantine-Notification-closeButton")
        for k in range(notices.count()):
            notices.nth(k).click()
        (ROOT / "docs").mkdir(exist_ok=True)
        pilot.screenshot(path=str(ROOT / "docs" / "screenshot.png"))


def test_a_second_viewer_watches_until_it_takes_control(pilot, viewer, demo: Demo) -> None:
    assert banner(viewer).startswith("View only")
    assert viewer.get_by_role("button", name="land", exact=True).is_disabled()
    assert viewer.locator("[data-gcs-off] [data-gcs-pad=move]").count() == 1
    assert viewer.get_by_role("button", name="ABORT: hold, then land").is_enabled()

    # its keys and its stick do not reach the operator command
    viewer.keyboard.down("d")
    pad = viewer.locator("[data-gcs-pad=move]").bounding_box()
    viewer.mouse.move(pad["x"] + pad["width"] / 2, pad["y"] + pad["height"] / 2)
    viewer.mouse.down()
    viewer.mouse.move(pad["x"] + pad["width"] / 2, pad["y"], steps=3)
    time.sleep(1.0)
    assert (operator(viewer)["fwd"], operator(viewer)["right"]) == (0.0, 0.0)
    viewer.mouse.up()
    viewer.keyboard.up("d")

    pilot_holder = text(viewer, "control")
    viewer.get_by_role("button", name="Take control").click()
    wait_for(lambda: banner(viewer) == "You hold control.", 10, "second viewer in control")
    wait_for(lambda: banner(pilot).startswith("View only"), 10, "first viewer now watching")
    wait_for(lambda: text(viewer, "control") != pilot_holder, 5, "new holder shown")
    viewer_id = text(viewer, "control").removeprefix("viewer #")
    keyboard = viewer.keyboard
    # c1 = 0.17/s: the team needs seconds to pick up speed; hold long enough under load
    dv = steer(demo, lambda: keyboard.down("a"), lambda: keyboard.up("a"), hold=3.5)
    assert dv[1] < -0.1, (
        f"velocity change {dv} m/s (forward, right) with A; expected left; "
        f"{situation(viewer, demo)}")
    assert operator(viewer)["source"] == f"browser#{viewer_id}"

    # the first viewer's keys are now ignored (once A's release has reached the loop:
    # beside two CPU hogs the page still showed A's -1 a second after it)
    wait_for(lambda: operator(pilot)["right"] == 0.0, 5, "sticks centred after A")
    pilot.keyboard.down("d")
    time.sleep(1.0)
    assert operator(pilot)["right"] == 0.0
    pilot.keyboard.up("d")


SMALL = {"width": 1024, "height": 600}
"""A small window: the scene between two panels, or the panels collapsed."""


def aborts(page) -> list[float]:  # type: ignore[no-untyped-def]
    """When the page's events list says the flight went into abort, s."""
    return [float(t) for t in re.findall(r"([0-9.]+) s phase: aborting", text(page, "events"))]


def abort_answers(page) -> tuple[int, str]:  # type: ignore[no-untyped-def]
    """How many answers the page's overlay ABORT has had, and the latest ("sent",
    "refused", "offline"; see web._browser_script.ABORT_ANSWERS)."""
    count, latest = page.locator("[data-gcs=abort]").evaluate(
        "a => [Number(a.dataset.gcsAnswers || 0), a.dataset.gcsAnswer || '']")
    return int(count), str(latest)


def test_the_abort_stays_in_view_and_any_viewer_aborts(pilot, viewer, demo: Demo,
                                                       screens: Path) -> None:
    """The holder, its focus still on the guidance checkbox it just clicked (where viser's
    own hotkey listener ignores keys), aborts with Ctrl+Shift+X while it holds D: the team
    stops and lands. The pilot's page (without control now) at 1024x600, both panels
    collapsed: its red ABORT is on screen and on top, and pressed during the abort it is
    answered "ABORT sent" by the server. The panel's own ABORT, expanded again, is
    answered too, and the landing team is not called back into the abort's hold."""
    # guidance off and on again: the checkbox keeps the focus (it takes no flight keys)
    guidance = viewer.get_by_label("guidance on")
    for shown in ("guidance off", "guidance on"):
        guidance.click()
        wait_for(lambda s=shown: s in text(viewer, "operator"), 5, f"{shown} shown")
    # the holder steers east at once (back from the west the last test flew to, away
    # from the geofence, whose breach would freeze and abort by itself) and keeps D held
    keyboard = viewer.keyboard
    keyboard.down("d")
    try:
        commanded(viewer, "right", lambda v: v > 0.9, "right > 0.9 while D is held")()
        pilot.set_viewport_size(SMALL)
        abort = pilot.locator("[data-gcs=abort]")

        def in_view() -> None:
            box = abort.bounding_box()
            assert box is not None and abort.is_visible(), "no ABORT on the page"
            assert (box["x"] >= 0 and box["y"] >= 0
                    and box["x"] + box["width"] <= SMALL["width"]
                    and box["y"] + box["height"] <= SMALL["height"]), f"ABORT at {box}: off"
            on_top = pilot.evaluate("([x, y]) => document.elementFromPoint(x, y).dataset.gcs",
                                    [box["x"] + box["width"] / 2, box["y"] + box["height"] / 2])
            assert on_top == "abort", f"ABORT at {box} is covered"
            # the freshness badge: on screen too, above the button, never over it
            badge = pilot.locator("[data-gcs=freshness]")
            over = badge.bounding_box()
            assert over is not None and badge.is_visible(), "no freshness badge on the page"
            assert (over["x"] >= 0 and over["y"] >= 0
                    and over["x"] + over["width"] <= SMALL["width"]), f"badge at {over}: off"
            assert over["y"] + over["height"] <= box["y"], f"badge at {over} over ABORT at {box}"

        in_view()
        panel_abort = pilot.get_by_role("button", name="ABORT: hold, then land")
        for side in ("right", "left"):
            pilot.locator(f"[data-dock-region-collapse={side}]").click()
        wait_for(lambda: panel_abort.count() == 0, 5, "the control panel collapsed")
        in_view()
        shot = screens / "abort-panels-collapsed.png"
        pilot.screenshot(path=str(shot))
        print(f"small window, panels collapsed: {shot}")

        # the team flies right (D), well inside the geofence; the holder aborts from the keyboard
        wait_for(lambda: demo.velocity()[1] > 0.05, 10, "the team flying right with D held",
                 lambda: situation(viewer, demo))
        moving = demo.velocity()
        where = np.asarray(demo.sample().vehicle_p_ned)
        centre = where.mean(axis=0)
        assert np.abs(where[:, :2]).max() < 3.7, f"vehicles at {where}: at the geofence (4 m)"
        assert guidance.evaluate("box => box === document.activeElement"), (
            "the guidance checkbox lost the focus")
        keyboard.press("Control+Shift+X")
        aborted = demo.sample().t  # sim time: the simulator lags the wall clock under load
        wait_for(lambda: bool(aborts(viewer)), 5, "phase: aborting after Ctrl+Shift+X in the "
                 "checkbox", lambda: situation(viewer, demo))
        first = max(aborts(viewer))
        # the pilot's overlay, pressed now: the server answers that it got it
        answers = abort_answers(pilot)[0]
        abort.click()
        wait_for(lambda: abort_answers(pilot)[0] > answers, 5, "the overlay's abort answered",
                 lambda: situation(viewer, demo))
        said = abort.inner_text()
        assert abort_answers(pilot)[1] == "sent" and said == ABORT_ANSWERS["sent"], (
            f"overlay: {abort_answers(pilot)}, {said!r}")
        demo.sample(after=aborted + 3.0)
        held = demo.velocity()
    finally:
        keyboard.up("d")
    speed, still = float(np.linalg.norm(moving)), float(np.linalg.norm(held))
    print(f"abort with D held at {centre[:2]} m: team speed {speed:.3f} -> {still:.3f} m/s "
          "in 3 s")
    assert still < 0.1 and still < 0.5 * speed, (
        f"the team still moves at {held} m/s 3 s after the abort; {situation(viewer, demo)}")
    wait_for(lambda: text(viewer, "phase") in ("landing", "landed"), 10,
             "landing after the abort's hold", lambda: situation(viewer, demo))

    # the control panel's ABORT, back in view, is answered for a viewer without control too:
    # taken while landing (the team lands on), or (the team already down) refused, saying why
    expand = pilot.locator('[aria-label="Expand column"]')
    boxes = [expand.nth(k).bounding_box() for k in range(expand.count())]
    expand.nth(max(range(len(boxes)), key=lambda k: boxes[k]["x"])).click()  # the right one
    answers = abort_answers(pilot)[0]
    panel_abort.click()
    wait_for(lambda: abort_answers(pilot)[0] > answers, 5, "the panel's abort answered",
             lambda: situation(viewer, demo))
    if abort_answers(pilot)[1] == "refused":
        pilot.get_by_text("cannot abort while landed").wait_for(timeout=5_000)
    time.sleep(0.5)  # a tick or two: the landing team is not called back into the hold
    assert not any(t > first for t in aborts(viewer)), situation(viewer, demo)
    assert text(viewer, "phase") in ("landing", "landed"), situation(viewer, demo)


def test_ctrl_c_stops_the_demo_and_its_simulator(demo: Demo) -> None:
    demo.proc.send_signal(signal.SIGINT)
    try:
        status = demo.proc.wait(30)
    except subprocess.TimeoutExpired:
        demo.proc.send_signal(signal.SIGUSR1)  # gcs dumps where each thread stood
        time.sleep(2.0)
        pytest.fail("gcs demo did not stop within 30 s of Ctrl-C:\n" + "".join(demo.err[-80:]))
    assert status == 0, "".join(demo.err[-10:])
    host, port = demo.endpoint.removeprefix("tcp/").rsplit(":", 1)
    with pytest.raises(OSError), socket.create_connection((host, int(port)), timeout=2):
        pass  # nothing listens on the simulator's endpoint any more


def test_the_overlay_abort_says_not_connected_once_the_page_is_gone(pilot) -> None:  # type: ignore[no-untyped-def]
    """The demo stopped: the page's websocket is down, viser drops what it would send, and
    the overlay, above viser's "disconnected" layer, must not say "sent"; the badge says
    STALE."""
    answers = abort_answers(pilot)[0]
    abort = pilot.locator("[data-gcs=abort]")
    abort.click()
    wait_for(lambda: abort_answers(pilot)[0] > answers, 5, "the overlay's abort answered")
    said = abort.inner_text()
    assert abort_answers(pilot)[1] == "offline" and said == ABORT_ANSWERS["offline"], (
        f"overlay: {abort_answers(pilot)}, {said!r}")
    # and its badge says how long it has heard nothing, trying to reconnect
    wait_for(lambda: "(reconnecting)" in freshness(pilot)["text"], 2 * RECONNECT_AFTER_S,
             "the badge reconnecting", lambda: str(freshness(pilot)))
    assert freshness(pilot)["state"] == "stale", freshness(pilot)
