"""The replay page: a recorded flight drawn by the live page's scene and plots.

The scene (:class:`~web.SceneView`, :func:`~web.build_frame`) and the
plots (:class:`~web._history.History`, :class:`~web._plots.PlotsView`) are the live
ones, fed from a :class:`~web._replay.ReplayCursor` instead of the links; the
status is a replay summary (nothing of the live loop's health is recorded). The
right panel holds the timeline instead of the operator controls: a replay has
no vehicles to command, so no operator control is created at all.
"""

from __future__ import annotations

import html
import math
import threading
import time

import numpy as np
import viser

from gcs.common import join_thread
from gcs.flightlog import FlightLog
from gcs.loop import Phase
from web._camera import CENTRE_HOTKEY, CENTRE_LABEL, ViewControls
from web._frame import SceneFrame, build_frame, frame_reach
from web._history import History
from web._plots import PlotsView
from web._quadmesh import quad_mesh
from web._replay import ReplayCursor, ReplayState, replay_view
from web._scene import SceneView
from web._status import event_filter_html, events_html, vehicle_table_html
from web._timeline import SPEEDS, Timeline
from web._trails import Trails
from web._ui import page_url
from web._viser_threads import leaving_allowed, wake_on_loop

__all__ = ["ReplayUi", "replay_summary_html", "run_replay"]

BEBOP_ARM = (0.0826, 0.0826)
"""Arm geometry of the drawn vehicle model (the log does not record the airframe), m."""

_JUMP = 2.0
"""A move of the play head by more than this (or backwards) rebuilds trails and plots, s."""

_DIV = '<div style="padding:2px 8px;font-size:0.85em;line-height:1.5">'


def _num(x: float, fmt: str) -> str:
    return "–" if not math.isfinite(x) else f"{x:{fmt}}"


def replay_summary_html(state: ReplayState, *, start: float, name: str,
                        missing: list[str], damage: str | None = None) -> str:
    """Replay time, phase, the recorded command and worst error, and what the log lacks.

    ``damage`` (:meth:`~gcs.flightlog.TlogIndex.damage`) is shown beside what is
    missing: a cut or corrupt log lacks what its damaged records held.
    """
    phase = state.phase.text if state.phase is not None else "–"
    v = state.values
    err = state.arrays.get("dist_err")
    worst = float(np.nanmax(np.abs(err))) if err is not None and np.isfinite(err).any() \
        else math.nan
    command = (f"fwd {_num(v.get('stk_fwd', math.nan), '+.2f')} · "
               f"right {_num(v.get('stk_rgt', math.nan), '+.2f')} · "
               f"rot {_num(v.get('stk_rot', math.nan), '+.2f')} · "
               f"scale {_num(v.get('scale', math.nan), '.2f')} · "
               f"alt {_num(v.get('alt_tgt', math.nan), '.2f')} m")
    payload = "–"
    if state.truth is not None:
        x, y, z = state.truth.payload_p_ned
        payload = f"{-z:.2f} m up at ({x:.2f}, {y:.2f}) m (simulator)"
    lack = "".join(f"<li>{html.escape(m)}</li>" for m in missing)
    if damage is not None:
        lack += f'<li data-gcs="damaged">damaged log: {html.escape(damage)}</li>'
    return (f'{_DIV}<div><b>REPLAY</b> of {html.escape(name)} at '
            f'<span data-gcs="replay-time">{state.t - start:.2f}</span> s</div>'
            f'<div>phase <b data-gcs="phase" style="font-size:1.2em">{phase}</b> · '
            f'worst distance error {_num(worst, ".3f")} m</div>'
            f'<div>command {command}</div><div>payload {payload}</div>'
            f'<div data-gcs="missing" style="color:#e67e22">missing from the log:'
            f'<ul style="margin:0">{lack or "<li>nothing</li>"}</ul></div></div>')


def _vehicles_html(state: ReplayState, stale_after: float) -> str:
    """The live page's vehicles table at the replayed moment (rope tension: simulation only,
    the airframe's mass that the live estimate needs is not recorded)."""
    f = state.fleet
    truth = state.truth
    rope = np.array([truth.rope_tension[truth.ids.index(vid)] for vid in f.ids]) \
        if truth is not None and set(truth.ids) >= set(f.ids) else np.full(f.n, np.nan)
    return vehicle_table_html(f, stale_after=stale_after, rope=rope, rope_head="rope N (sim)",
                              health={}, heartbeat_age=f.heartbeat_age)


class ReplayUi:
    """Serve the replay of ``log``; ``start()`` then ``close()``.

    Args:
        log: the loaded flight.
        name: what to call it on the page (the file name).
        host: interface to serve on.
        port: TCP port of the page.
        rate_hz: scene frames per second.
    """

    def __init__(self, log: FlightLog, *, name: str = "flight", host: str = "127.0.0.1",
                 port: int = 8080, rate_hz: float = 25.0) -> None:
        self.cursor = ReplayCursor(log)
        self.view = replay_view(self.cursor)
        self.timeline = Timeline(self.cursor.start, self.cursor.end)
        self.host = host
        self._name = name
        self._period = 1.0 / rate_hz
        self.server = viser.ViserServer(host=host, port=port, label=f"GCS replay {name}",
                                        verbose=False)
        server = self.server
        wake_on_loop(server)  # drawn from this page's thread and viser's callbacks
        server.gui.configure_theme(control_width="large", show_share_button=False)
        server.gui.main_panel.dock_right()
        self._scene = SceneView(server.scene, self.view, quad_mesh(*BEBOP_ARM),
                                geofence_xy=self._extent())
        server.initial_camera.position = (-3.4, -1.0, -2.4)
        server.initial_camera.look_at = (0.0, 0.0, 0.0)
        info = server.gui.add_panel()
        info.dock_left()
        info.set_width(470)
        ids = self.view.ids
        labels = tuple(f"{ids[a]}-{ids[b]}" for a, b in self.view.edges)
        with info.add_tab("Status", viser.Icon.LIST_DETAILS):
            self._summary = server.gui.add_html("")
            self._vehicles = server.gui.add_html("")
            server.gui.add_html(event_filter_html())
            self._events = server.gui.add_html("")
        with info.add_tab("Plots", viser.Icon.CHART_LINE):
            # the charts need the team's edges; a plain autopilot log has none
            self._plots = PlotsView(server.gui, self.view, labels) if labels else None
            if self._plots is None:
                server.gui.add_html(f"{_DIV}no plots: the log has no team header</div>")
        self._add_timeline(server.gui)
        self._history = History(self.view)
        self._trails = Trails(self.view.n)
        self._views: dict[int, ViewControls] = {}  # each viewer's camera, by client id
        self._views_lock = threading.Lock()
        self._frame: SceneFrame | None = None
        self._reframe = False  # the replay reached the landing: frame the team again
        self._landed = False
        centre = server.gui.add_command(CENTRE_LABEL, hotkey=CENTRE_HOTKEY,
                                        icon=viser.Icon.FOCUS_CENTERED,
                                        description="this viewer: look at the team again")
        centre.on_trigger(self._on_centre)
        server.on_client_connect(self._on_connect)
        server.on_client_disconnect(self._on_disconnect)
        self._shown_t: float | None = None
        self._events_shown = -1
        self._shown_tick = -2
        self._echo = threading.local()
        self._draw_lock = threading.Lock()  # the UI thread and viewers' callbacks both draw
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True, name="replay-ui")
        self.draw()

    # -- public --------------------------------------------------------------------------

    @property
    def url(self) -> str:
        """Where to point a browser."""
        return page_url(self.host, self.server)

    def start(self) -> None:
        self._thread.start()

    def close(self) -> None:
        """Stop drawing and serving; idempotent."""
        self._stop.set()
        join_thread(self._thread, 2.0, what="the replay page's drawing loop")
        with self._draw_lock:  # a viewer's callback drawing now ends first; later ones
            pass               # see the page stopped (and viser's pool is not waited on here)
        self.server.stop()

    def seek(self, t: float) -> None:
        """Move the play head to log time ``t`` and draw it now."""
        self.timeline.seek(t)
        self.draw()

    # -- viewers' cameras ----------------------------------------------------------------

    def _on_connect(self, client: viser.ClientHandle) -> None:
        view = ViewControls(client)
        with self._views_lock:
            self._views[client.client_id] = view

    def _on_disconnect(self, client: viser.ClientHandle) -> None:
        with self._views_lock:
            self._views.pop(client.client_id, None)

    def _on_centre(self, event: viser.CommandEvent) -> None:
        with self._views_lock:
            view = self._views.get(event.client_id) if event.client_id is not None else None
        if view is not None:
            view.request_centre()

    def _follow(self) -> None:
        """Every viewer's camera on the team as last drawn (the UI thread, each period)."""
        frame = self._frame
        if frame is None:
            return
        reframe, self._reframe = self._reframe, False
        team_reach = frame_reach(frame)
        with self._views_lock:
            views = list(self._views.values())
        with leaving_allowed(v.client for v in views):
            for view in views:
                view.update(frame.centroid, team_reach, reframe=reframe)

    # -- timeline controls ---------------------------------------------------------------

    def _add_timeline(self, gui: viser.GuiApi) -> None:
        tl = self.timeline
        gui.add_markdown(f"**Replay** of `{self._name}`: a recording, so the operator "
                         "controls (sticks, phases, ABORT) are not available.")
        with gui.add_folder("Timeline"):
            self._play = gui.add_button("Play", icon=viser.Icon.PLAYER_PLAY)
            self._pause = gui.add_button("Pause", icon=viser.Icon.PLAYER_PAUSE)
            self._speed = gui.add_dropdown("Speed", tuple(f"{s:g}x" for s in SPEEDS),
                                           initial_value="1x")
            self._slider = gui.add_slider("Time (s)", min=0.0, max=max(tl.duration, 0.1),
                                          step=0.05, initial_value=0.0)
            names = tuple(f"{e.t - tl.start:6.1f} s {e.text}"[:60] for e in self.cursor.events)
            self._event_names = names
            self._event = gui.add_dropdown("Event", names or ("(no events)",))
            self._jump = gui.add_button("Jump to event", disabled=not names)
            self._prev = gui.add_button("Previous event", disabled=not names)
            self._next = gui.add_button("Next event", disabled=not names)

        self._play.on_click(lambda _: tl.play())
        self._pause.on_click(lambda _: tl.pause())
        self._speed.on_update(lambda _: setattr(tl, "speed", float(self._speed.value[:-1])))
        self._slider.on_update(self._on_slider)
        self._jump.on_click(lambda _: self._jump_to_selected())
        self._prev.on_click(lambda _: self._step_event(-1))
        self._next.on_click(lambda _: self._step_event(+1))

    def _on_slider(self, _: object) -> None:
        if getattr(self._echo, "active", False):
            return
        target = self.timeline.start + float(self._slider.value)
        self.seek(target)

    def _jump_to_selected(self) -> None:
        if self._event.value in self._event_names:
            self.seek(self.cursor.events[self._event_names.index(self._event.value)].t)

    def _step_event(self, direction: int) -> None:
        times = [e.t for e in self.cursor.events]
        t = self.timeline.t
        later = [x for x in times if x > t + 1e-6] if direction > 0 else \
            [x for x in times if x < t - 1e-6]
        if later:
            self.seek(later[0] if direction > 0 else later[-1])

    # -- drawing -------------------------------------------------------------------------

    def _extent(self) -> float:
        """Half-size of the drawn ground: the flight's reach plus a margin (no geofence is
        recorded)."""
        reach = [float(np.nanmax(np.abs(tr.p_ned[:, :2]))) for tr in
                 self.cursor.log.tracks.values() if len(tr.t)]
        return max(reach, default=1.0) + 1.0

    def _run(self) -> None:
        last = time.monotonic()
        while not self._stop.wait(self._period):
            now = time.monotonic()
            self.timeline.advance(now - last)
            last = now
            self.draw(only_moved=True)
            self._follow()

    def _rebuild(self, t: float) -> None:
        """Trails and plots as they were at ``t`` (after a jump)."""
        self._trails = Trails(self.view.n)
        for s in np.arange(max(t - 10.0, self.timeline.start), t, self._trails.period):
            self._trails.add(float(s), self.cursor.fleet(float(s)).p_ned)
        self._history = History(self.view)
        self._shown_tick = self.cursor.tick(t - self._history.window) - 1

    def draw(self, *, only_moved: bool = False) -> None:
        """Draw the recorded state at the play head: scene every call, status and plots per
        tick. The play head is read under the draw lock, so a seek's drawing is never
        overwritten by a time this thread read before the seek. ``only_moved``: nothing to
        do when the play head is where it was last drawn."""
        with self._draw_lock:
            if self._stop.is_set():  # closed: a callback's late seek (viser answers our own
                return               # slider writes too) must not write to a stopped server
            t = self.timeline.t
            if not (only_moved and t == self._shown_t):
                self._draw(t)

    def _draw(self, t: float) -> None:
        last = self._shown_t
        if last is None or t < last or t - last > _JUMP:
            self._rebuild(t)
        self._shown_t = t
        state = self.cursor.state(t)
        self._trails.add(t, state.fleet.p_ned)
        frame = build_frame(self.view, state.fleet, scale=state.scale, truth=state.truth,
                            trails=self._trails)
        self._frame = frame
        landed = state.phase is Phase.LANDED
        if landed and not self._landed:
            self._reframe = True
        self._landed = landed
        log = self.cursor.log
        with self.server.atomic():
            self._scene.draw(frame)
            self._echo.active = True  # viser calls on_update for our own writes too
            try:
                # writable: viser 1.1's setter is not next to its getter, so mypy misses it
                self._slider.value = round(t - self.timeline.start, 2)  # type: ignore[misc]
            finally:
                self._echo.active = False
            if state.tick != self._shown_tick or last is None:
                for k in range(max(self._shown_tick + 1, 0), state.tick + 1):
                    tk = float(log.tick_t[k])
                    f = self.cursor.fleet(tk)
                    s = float(log.values["scale"][k]) if "scale" in log.values else 1.0
                    self._history.add_sample(tk, f.p_ned, f.v_ned, s if math.isfinite(s) else 1.0)
                self._shown_tick = state.tick
                if self._plots is not None:
                    self._plots.update(self._history)
            self._summary.content = replay_summary_html(
                state, start=self.timeline.start, name=self._name, missing=log.missing,
                damage=log.index.damage())
            self._vehicles.content = _vehicles_html(state, self.view.stale_after)
            if len(state.events) != self._events_shown:  # the log grows by events only
                self._events_shown = len(state.events)
                self._events.content = events_html(state.events, start=self.timeline.start)


def run_replay(log: FlightLog, *, name: str, host: str, port: int) -> int:
    """Serve the replay of ``log`` (called ``name`` on the page) until Ctrl-C.

    Prints the page's address and, for a damaged log, the same note as ``gcs
    report`` (what could not be read), which the page shows too.
    """
    ui = ReplayUi(log, name=name, host=host, port=port)
    try:
        ui.start()
        print(f"GCS replay: {ui.url}  (Ctrl-C to stop)", flush=True)
        damage = log.index.damage()
        if damage is not None:
            print(f"note: {damage}", flush=True)
        while True:
            time.sleep(0.5)
    except KeyboardInterrupt:
        print("stopping…", flush=True)
        return 0
    finally:
        ui.close()
