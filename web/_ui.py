"""The live page of one GCS: a viser server and the thread that draws it.

The 4 Hz loop is never made to wait for the page: its listener only stores
the latest snapshot. A separate UI thread draws the scene at ``rate_hz``
(25 Hz by default) from the vehicles' latest telemetry and the simulator's
truth, each frame inside ``server.atomic()``; the status and plots follow the
loop's snapshots, and every viewer gets a *beat* with each of them (and at
least every 0.25 s): the GCS time of the latest tick and its age, from which
the page's badge says how old its data is (``web._browser_script``). Every
buffer of the server wakes its sender on viser's loop only
(``web._viser_threads``): this thread and viser's callbacks write from other
threads. The holder's sticks are written to the operator command
from this thread too (refreshed while deflected, one zero on release), so the
browser is one more input source beside the gamepad and scripts.

Layout of the page: the 3-D scene in the middle, under a red ABORT button
that no panel can hide (the page script's; it presses the abort command's
hotkey, Ctrl+Shift+X); the control panel on the
right has, per viewer, the control banner, ABORT, take/release control, the
"Fly" folder (virtual sticks, scale, altitude, guidance, phase buttons) and
"View"; a panel on the left, shared by all viewers, has the tabs "Status"
(phase, command, vehicles and links, events) and "Plots" (distances and
velocities over the last 60 s).
"""

from __future__ import annotations

import collections
import logging
import math
import socket
import threading
import time

import numpy as np
import viser

from gcs.app import GcsApp
from gcs.common import join_thread
from gcs.loop import Action, Phase, RuntimeSnapshot
from gcs.wire import SystemStatus
from web._actions import OperatorActions
from web._browser_script import (
    ABORT_HOTKEY,
    ABORT_LABEL,
    ABORT_MODIFIER,
    BEAT_PERIOD_S,
    beat,
    install_script,
)
from web._camera import CENTRE_HOTKEY, CENTRE_LABEL
from web._control_lock import ControlLock
from web._events import EventLog
from web._frame import SceneFrame, TeamView, build_frame, frame_reach
from web._history import History
from web._link_quality import LinkQuality
from web._panel import ControlPanel, abort_for
from web._plots import PlotsView
from web._quadmesh import quad_mesh
from web._scene import SceneView
from web._status import (
    UiStats,
    event_filter_html,
    events_html,
    position_sources,
    summary_html,
    vehicles_html,
)
from web._trails import Trails
from web._viser_threads import leaving_allowed, wake_on_loop

__all__ = ["UI_RATE_HZ", "WebUi", "page_url"]

_log = logging.getLogger(__name__)

UI_RATE_HZ = 25.0
"""Scene frames per second of the UI thread (the issue asks at least 20)."""


def page_url(host: str, server: viser.ViserServer) -> str:
    """Where a browser reaches ``server`` served on ``host`` (the machine's name for any)."""
    name = socket.gethostname() if host in ("0.0.0.0", "::") else host
    return f"http://{name}:{server.get_port()}"


class WebUi:
    """Serve the page of ``app`` and draw it; ``start()`` then ``close()``.

    Args:
        app: the GCS (runtime, operator, clock, team, sim truth).
        host: interface to serve on; 127.0.0.1 unless another is asked for.
        port: TCP port of the page (and its websocket).
        rate_hz: scene frames per second.
    """

    def __init__(self, app: GcsApp, *, host: str = "127.0.0.1", port: int = 8080,
                 rate_hz: float = UI_RATE_HZ) -> None:
        self._app = app
        runtime = app.loop
        cfg = app.team.config
        self._view = TeamView.from_team(app.team, runtime.analysis)
        self._period = 1.0 / rate_hz
        self.host = host
        self.server = viser.ViserServer(host=host, port=port, label=f"GCS {cfg.name}",
                                        verbose=False)
        server = self.server
        wake_on_loop(server)
        server.gui.configure_theme(control_width="large", show_share_button=False)
        server.gui.main_panel.dock_right()
        abort = server.gui.add_command(ABORT_LABEL, hotkey=ABORT_HOTKEY, modifier=ABORT_MODIFIER,
                                       icon=viser.Icon.ALERT_OCTAGON,
                                       description="any viewer: the team stops, holds, lands")
        abort.on_trigger(self._on_abort)
        centre = server.gui.add_command(CENTRE_LABEL, hotkey=CENTRE_HOTKEY,
                                        icon=viser.Icon.FOCUS_CENTERED,
                                        description="this viewer: look at the team again")
        centre.on_trigger(self._on_centre)
        install_script(server)
        self._scene = SceneView(server.scene, self._view,
                                quad_mesh(cfg.airframe.arm_x, cfg.airframe.arm_y),
                                geofence_xy=cfg.safety.geofence_xy,
                                geofence_margin=cfg.safety.geofence_margin)
        # behind the team (south, its forward is north) and above: forward is away; each
        # viewer's camera is then framed on the team wherever it is (web._camera)
        server.initial_camera.position = (-3.4, -1.0, -2.4)
        server.initial_camera.look_at = (0.0, 0.0, 0.0)
        labels = tuple(app.team.formation.label(k) for k in range(app.team.formation.m))
        # shared status and plots in their own panel on the left, so the controls
        # on the right keep the whole height (ABORT at their top)
        info = server.gui.add_panel()
        info.dock_left()
        info.set_width(470)
        with info.add_tab("Status", viser.Icon.LIST_DETAILS):
            self._summary = server.gui.add_html(summary_html(None, loop=None, control="",
                                                             ui=None))
            self._vehicles = server.gui.add_html("")
            server.gui.add_html(event_filter_html())
            self._events = server.gui.add_html(events_html(()))
        with info.add_tab("Plots", viser.Icon.CHART_LINE):
            self._plots = PlotsView(server.gui, self._view, labels)
        self._history = History(self._view)
        self._trails = Trails(self._view.n)
        self._event_log = EventLog()
        self._quality = LinkQuality()
        self._sources = position_sources(app.team)
        self._landed_seen = False  # a landing the viewers' cameras were framed on already
        self._lock = ControlLock()
        self._actions = OperatorActions(runtime, app.operator, app.clock)
        self._panels: dict[int, ControlPanel] = {}
        self._panels_lock = threading.Lock()
        # the loop's latest snapshot and when it came (monotonic; before the first: now)
        self._latest: tuple[RuntimeSnapshot | None, float] = (None, time.monotonic())
        self._beat_at = -math.inf
        self._shown: RuntimeSnapshot | None = None
        self._sticks_active = False
        self._last_error = ""
        self._frame_times: collections.deque[float] = collections.deque(maxlen=100)
        self._frame_costs: collections.deque[float] = collections.deque(maxlen=100)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True, name="web-ui")
        server.on_client_connect(self._on_connect)
        server.on_client_disconnect(self._on_disconnect)
        app.add_listener(self._on_tick)

    # -- public --------------------------------------------------------------------------

    @property
    def url(self) -> str:
        """Where to point a browser."""
        return page_url(self.host, self.server)

    def browser_holds_control(self) -> bool:
        """True while a viewer holds control (then the gamepad may not steer)."""
        return self._lock.holder is not None

    def start(self) -> None:
        """Start drawing (the server is already serving)."""
        self._thread.start()

    def stats(self) -> UiStats:
        """Achieved frame rate and the server-side cost of a frame (build and draw)."""
        times = list(self._frame_times)
        rate = (len(times) - 1) / (times[-1] - times[0]) if len(times) > 2 else 0.0
        costs = np.array(self._frame_costs) if self._frame_costs else np.zeros(1)
        return UiStats(rate_hz=rate, draw_ms=1e3 * float(np.median(costs)),
                       draw_p99_ms=1e3 * float(np.percentile(costs, 99)))

    def close(self) -> None:
        """Stop drawing and serving; idempotent."""
        self._stop.set()
        join_thread(self._thread, 2.0, what="the page's drawing loop")
        self.server.stop()

    # -- viewers -------------------------------------------------------------------------

    def _on_connect(self, client: viser.ClientHandle) -> None:
        panel = ControlPanel(client, self._actions, self._lock,
                             on_control_change=self._refresh_panels)
        with self._panels_lock:
            self._panels[client.client_id] = panel
        panel.refresh()

    def _on_disconnect(self, client: viser.ClientHandle) -> None:
        with self._panels_lock:
            panel = self._panels.pop(client.client_id, None)
        if panel is not None and panel.close():
            self._refresh_panels()

    def _on_centre(self, event: viser.CommandEvent) -> None:
        """The centring command (key C, the palette): for the viewer it came from."""
        with self._panels_lock:
            panel = self._panels.get(event.client_id) if event.client_id is not None else None
        if panel is not None:
            panel.view.request_centre()

    def _on_abort(self, event: viser.CommandEvent) -> None:
        """The abort command (the overlay button, the hotkey): as the viewer's panel's."""
        with self._panels_lock:
            panel = self._panels.get(event.client_id) if event.client_id is not None else None
        if panel is not None:
            panel.abort()
        elif event.client is not None:  # a viewer whose panel is not built yet still aborts
            abort_for(event.client, self._actions)
        else:
            self._actions.request(Action.ABORT)

    def _refresh_panels(self) -> None:
        panels = self._panel_list()
        with leaving_allowed(p.client for p in panels):
            for panel in panels:
                panel.refresh()

    def _panel_list(self) -> list[ControlPanel]:
        """The viewers' panels, copied under the lock (viser's threads add and remove them)."""
        with self._panels_lock:
            return list(self._panels.values())

    def _control_text(self) -> str:
        holder = self._lock.holder
        return "nobody (view only)" if holder is None else f"viewer #{holder}"

    # -- drawing -------------------------------------------------------------------------

    def _on_tick(self, snap: RuntimeSnapshot, _truth: object) -> None:
        """The loop's listener: store, nothing else (the loop must never wait for the page)."""
        self._latest = (snap, time.monotonic())

    def _run(self) -> None:
        due = time.monotonic()
        while not self._stop.wait(max(0.0, due - time.monotonic())):
            now = time.monotonic()
            due = max(due + self._period, now - self._period)  # never burst to catch up
            try:
                self._frame()
            except Exception as exc:  # a bad frame must not end the page
                text = f"{type(exc).__name__}: {exc}"
                if text != self._last_error:  # once per distinct fault, not 25 times a second
                    self._last_error = text
                    _log.exception("UI frame failed")
            self._frame_times.append(now)

    def _frame(self) -> None:
        app = self._app
        started = time.perf_counter()
        fleet = app.loop.fleet_table.read(app.clock.now())
        snap, came = self._latest
        self._trails.add(fleet.t, fleet.p_ned)
        frame = build_frame(self._view, fleet, scale=snap.operator.demand.scale if snap else 1.0,
                            truth=app.truth, trails=self._trails,
                            accel_cmd=snap.accel_cmd if snap else None)
        with self.server.atomic():
            self._scene.draw(frame)
        self._frame_costs.append(time.perf_counter() - started)
        panels = self._panel_list()
        with leaving_allowed(p.client for p in panels):
            self._draw_panels(panels, frame, snap, came)

    def _draw_panels(self, panels: list[ControlPanel], frame: SceneFrame,
                     snap: RuntimeSnapshot | None, came: float) -> None:
        """Each viewer's own part of a frame: its sticks read, its camera, its panel,
        its beat."""
        self._write_sticks(panels)
        landed = snap is not None and snap.phase is Phase.LANDED
        reframe, self._landed_seen = landed and not self._landed_seen, landed
        team_reach = frame_reach(frame)
        for panel in panels:
            panel.view.update(frame.centroid, team_reach, reframe=reframe)
        ticked = snap is not None and snap is not self._shown
        if snap is not None and snap is not self._shown:
            self._shown = snap
            self._show_tick(snap, panels)
        self._beat(panels, snap, came, ticked=ticked)

    def _beat(self, panels: list[ControlPanel], snap: RuntimeSnapshot | None, came: float, *,
              ticked: bool) -> None:
        """Tell every viewer the GCS time of the latest tick and its age (with each tick,
        and at least every :data:`BEAT_PERIOD_S`): the page's freshness badge."""
        now = time.monotonic()
        if not ticked and now - self._beat_at < BEAT_PERIOD_S:
            return
        self._beat_at = now
        gcs_time = snap.fleet.t if snap is not None else None
        for panel in panels:
            beat(panel.client, gcs_time=gcs_time, age=now - came)

    def _write_sticks(self, panels: list[ControlPanel]) -> None:
        holder = self._lock.holder
        panel = next((p for p in panels if p.id == holder), None)
        if panel is None:
            self._sticks_active = False
            return
        sticks = panel.sticks()
        if any(sticks) or self._sticks_active:
            self._actions.set_sticks(*sticks, source=panel.source)
        self._sticks_active = any(sticks)

    def _show_tick(self, snap: RuntimeSnapshot, panels: list[ControlPanel]) -> None:
        app = self._app
        links = [app.loop.profiles[vid].link for vid in self._view.ids]
        health = {vid: link.health for vid, link in zip(self._view.ids, links, strict=True)}
        voltage = np.array([_volts(link.telemetry.status) for link in links])
        quality = self._quality.update(time.monotonic(), health)
        new_events = self._event_log.take(app.loop.events())
        with self.server.atomic():
            self._summary.content = summary_html(
                snap, loop=app.loop.stats(), control=self._control_text(), ui=self.stats(),
                unsigned=[vid for vid, h in health.items() if not h.signed])
            self._vehicles.content = vehicles_html(
                snap, health=health, truth=snap.truth, mass=app.team.config.airframe.mass,
                stale_after=self._view.stale_after, voltage=voltage, quality=quality,
                sources=self._sources)
            if new_events:
                self._events.content = events_html(self._event_log.events)
            if self._history.add(snap):
                self._plots.update(self._history)
        for panel in panels:
            panel.sync(snap.operator)


def _volts(status: SystemStatus | None) -> float:
    """A SYS_STATUS's battery voltage, V (NaN: none, or the autopilot does not know)."""
    if status is None or status.battery_voltage_v is None:
        return math.nan
    return status.battery_voltage_v
