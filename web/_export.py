"""``gcs replay FILE --export flight.html``: the replay as one file a browser opens offline.

Why this way: viser 1.1 records a scene (``ViserServer.get_scene_serializer``)
and writes it as one standalone page that holds its own client
(``StateSerializer.as_html``). The replay page's own code (:class:`ReplayUi`)
draws every frame into that recording, so the exported scene is the live
replay's, vehicles, ropes, payload, shape and ground marks included, and it
plays from a ``file://`` URL with no server and no network.

The recording holds the scene only (viser leaves GUI messages out), so the
rest of the page travels beside it as gzipped JSON that ``export_page.js``
draws over viser's client: the status, the vehicles table and the events as
the replay page renders them at each frame (the same HTML functions), the
plots of the whole flight, and a timeline with the phases and events. That
script owns the time: it hides viser's playback bar and moves viser's
playback to each frame it shows.
"""

from __future__ import annotations

import base64
import contextlib
import errno
import gzip
import html
import io
import json
import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from gcs.app import free_tcp_port
from gcs.flightlog import PHASE_SHADES, FlightLog
from gcs.loop import Phase
from web._history import History
from web._plots import _COLORS, MAX_SERIES
from web._replay import ReplayCursor
from web._replay_page import ReplayUi, _vehicles_html, replay_summary_html
from web._status import event_filter_html, events_html
from web._timeline import SPEEDS

__all__ = ["EXPORT_RATE_HZ", "MAX_FRAMES", "ExportResult", "export_replay", "run_export"]

EXPORT_RATE_HZ = 10.0
"""Frames per second of flight in the exported file (scene, status and vehicles table).
The GCS decides at 4 Hz; 90 s of flight at 10 Hz is about 1.5 MB."""

MAX_FRAMES = 9000
"""At most this many frames (15 min at 10 Hz): a longer flight is exported at a lower rate,
so the page a browser holds stays near 100 MB whatever the log's length."""

_SCRIPT_FILE = "export_page.js"
_MM = 1000  # positions in the data: integer millimetres
_EVENT_LEVELS = ("info", "warning", "error")


@dataclass(frozen=True)
class ExportResult:
    """What :func:`export_replay` wrote."""

    path: Path
    size: int  # bytes
    frames: int
    rate_hz: float
    duration: float  # s of flight
    seconds: float  # wall time the export took


class _Strings:
    """Distinct strings, each stored once: a frame refers to its panels by index."""

    def __init__(self) -> None:
        self.items: list[str] = []
        self._index: dict[str, int] = {}

    def add(self, s: str) -> int:
        k = self._index.get(s)
        if k is None:
            k = self._index[s] = len(self.items)
            self.items.append(s)
        return k


def _ints(a: np.ndarray, scale: float) -> list[int | None]:
    """``a`` times ``scale`` rounded, flat, None where not finite (compact JSON)."""
    flat = np.asarray(a, dtype=float).ravel() * scale
    ok = np.isfinite(flat)
    out: list[int | None] = np.where(ok, np.round(np.where(ok, flat, 0.0)), 0).astype(
        np.int64).tolist()
    for k in np.flatnonzero(~ok):
        out[k] = None
    return out


def _bands(log: FlightLog, start: float, end: float) -> list[list[float | str]]:
    """(from, to, colour, phase) of the shaded phases, s from ``start``: the report's key."""
    changes = log.phase_changes()
    out: list[list[float | str]] = []
    for k, (t, name) in enumerate(changes):
        stop = changes[k + 1][0] if k + 1 < len(changes) else end
        if name in PHASE_SHADES:
            out.append([round(t - start, 3), round(stop - start, 3), PHASE_SHADES[name], name])
    return out


def _chart(title: str, t: np.ndarray, lines: list[tuple[str, str, bool, np.ndarray]], *,
           zero: bool = False) -> dict[str, object]:
    """One chart's data: times in ms, each line's (label, colour, dashed, values) in
    thousandths of the title's unit; ``zero`` keeps 0 in view."""
    return {"title": title, "t": _ints(t, 1000), "scale": 1000, "zero": zero,
            "lines": [{"label": label, "colour": colour, "dash": dash, "y": _ints(y, 1000)}
                      for label, colour, dash, y in lines]}


def _charts(cursor: ReplayCursor, ui: ReplayUi) -> list[dict[str, object]]:
    """The whole flight's plots: the distance errors the guidance computed, the distances
    against their desired values and the velocities, as on the replay page."""
    log, view, start = cursor.log, ui.view, cursor.start

    def colour(k: int) -> str:  # the live plots' colours
        return _COLORS[k % len(_COLORS)]

    edges = range(min(len(view.edges), MAX_SERIES))
    labels = [f"{view.ids[a]}-{view.ids[b]}" for a, b in view.edges]
    out = []
    err = log.arrays.get("dist_err")
    if err is not None and len(edges):
        out.append(_chart("distance error (m)", log.tick_t - start,
                          [(labels[k], colour(k), False, err[:, k]) for k in edges], zero=True))
    history = History(view, window=math.inf)
    for k, tk in enumerate(log.tick_t):
        f = cursor.fleet(float(tk))
        scale = float(log.values["scale"][k]) if "scale" in log.values else 1.0
        history.add_sample(float(tk), f.p_ned, f.v_ned, scale if math.isfinite(scale) else 1.0)
    s = history.series()
    if not len(s.t):
        return out
    t = s.t - start
    if len(edges):
        _, first = np.unique(np.round(view.distances[list(edges)], 3), return_index=True)
        out.append(_chart("distances (m)", t,
                          [(labels[k], colour(k), False, s.distance[:, k]) for k in edges]
                          + [(f"desired {view.distances[k]:.2f}", "#000", True, s.desired[:, k])
                             for k in sorted(first)]))
    vehicles = range(min(view.n, MAX_SERIES))
    for name, v in (("velocity x, north (m/s)", s.vx), ("velocity y, east (m/s)", s.vy)):
        out.append(_chart(name, t, [(str(view.ids[i]), colour(i), False, v[:, i])
                                    for i in vehicles], zero=True))
    return out


def _camera(ui: ReplayUi, cursor: ReplayCursor) -> None:
    """The first view: the whole flight's ground track in sight, from the south-west and
    above (the live replay's bearing), since the exported page's camera cannot follow."""
    p = np.concatenate([tr.p_ned for tr in cursor.log.tracks.values() if len(tr.t)] or
                       [np.zeros((1, 3))])
    p = p[np.isfinite(p).all(axis=1)]
    if not len(p):
        return
    lo, hi = p.min(axis=0), p.max(axis=0)
    centre = (lo + hi) / 2
    centre[2] = min(float(centre[2]), 0.0)
    reach = max(float(np.max(hi[:2] - lo[:2])) / 2 + 1.5, 2.5)
    direction = np.array([-3.4, -1.0, -2.4])
    direction /= np.linalg.norm(direction)
    ui.server.initial_camera.look_at = centre
    ui.server.initial_camera.position = centre + 1.6 * reach * direction


def export_replay(log: FlightLog, out: str | Path, *, name: str,
                  rate_hz: float = EXPORT_RATE_HZ,
                  progress: Callable[[int, int], None] | None = None) -> ExportResult:
    """Write the replay of ``log`` (called ``name`` on the page) as one HTML file ``out``.

    ``rate_hz`` frames per second of flight, fewer for a flight longer than
    :data:`MAX_FRAMES` allows. ``progress(done, total)`` is called with the frames
    drawn. OSError if ``out`` cannot be written.
    """
    began = time.monotonic()
    out = Path(out)
    if not out.parent.is_dir():  # said before the work, not after it
        raise FileNotFoundError(errno.ENOENT, "no such directory", str(out.parent))
    # viser prints its address on start and stop: nothing is served here
    with contextlib.redirect_stdout(io.StringIO()):
        ui = ReplayUi(log, name=name, host="127.0.0.1", port=free_tcp_port())
        try:
            duration = ui.cursor.end - ui.cursor.start
            rate_hz = min(rate_hz, MAX_FRAMES / duration) if duration > 0 else rate_hz
            page, frames = _record(ui, name, rate_hz, progress)
        finally:
            ui.close()
    out.write_text(page, encoding="utf-8")
    return ExportResult(path=out, size=out.stat().st_size, frames=frames, rate_hz=rate_hz,
                        duration=duration,
                        seconds=time.monotonic() - began)


def _record(ui: ReplayUi, name: str, rate_hz: float,
            progress: Callable[[int, int], None] | None) -> tuple[str, int]:
    """Draw every frame into viser's recording and the panels' data; the page, frames."""
    cursor = ui.cursor
    log = cursor.log
    start = cursor.start
    frames = math.floor((cursor.end - start) * rate_hz) + 1
    _camera(ui, cursor)
    recording = ui.server.get_scene_serializer()
    strings = _Strings()
    panels: dict[str, list[int]] = {"summary": [], "vehicles": [], "events": []}
    positions = np.full((frames, cursor.n, 3), np.nan)
    phases = np.full(frames, -1, dtype=int)
    damage = log.index.damage()
    shown_events = -1
    events_at = 0
    for k in range(frames):
        t = start + k / rate_hz
        ui.seek(t)
        recording.insert_sleep(1.0 / rate_hz)
        state = cursor.state(t)
        positions[k] = state.fleet.p_ned
        phases[k] = -1 if state.phase is None else int(state.phase)
        panels["summary"].append(strings.add(replay_summary_html(
            state, start=start, name=name, missing=log.missing, damage=damage)))
        panels["vehicles"].append(strings.add(_vehicles_html(state, ui.view.stale_after)))
        if len(state.events) != shown_events:
            shown_events = len(state.events)
            events_at = strings.add(events_html(state.events, start=start))
        panels["events"].append(events_at)
        if progress is not None:
            progress(k + 1, frames)
    data = {
        "name": name, "hz": rate_hz, "frames": frames, "speeds": list(SPEEDS),
        "ids": list(cursor.ids), "pScale": _MM, "p": _ints(positions, _MM),
        "phase": phases.tolist(), "phaseNames": [p.text for p in Phase],
        "phases": [[round(t - start, 3), n] for t, n in log.phase_changes()],
        "bands": _bands(log, start, cursor.end),
        "events": [[round(e.t - start, 3), e.level if e.level in _EVENT_LEVELS else "info",
                    e.kind, e.text] for e in cursor.events],
        "html": {"strings": strings.items, "filter": event_filter_html(), **panels},
        "charts": _charts(cursor, ui),
    }
    page = recording.as_html()
    return _with_overlay(page, name, data), frames


def _with_overlay(page: str, name: str, data: dict[str, object]) -> str:
    """viser's standalone page with the replay's title, data and script in its head."""
    packed = base64.b64encode(gzip.compress(
        json.dumps(data, separators=(",", ":"), allow_nan=False).encode(), 9, mtime=0))
    script = resources.files("web").joinpath(_SCRIPT_FILE).read_text(encoding="utf-8")
    head = (f'<script>window.__GCS_EXPORT__="{packed.decode("ascii")}";</script>'
            f"<script>{script}</script>")
    page = page.replace("<title>Viser</title>",
                        f"<title>GCS replay {html.escape(name)}</title>", 1)
    at = page.index("</head>")
    return page[:at] + head + page[at:]


def run_export(log: FlightLog, out: str | Path, *, name: str, quiet: bool = False) -> int:
    """``gcs replay FILE --export OUT``: write the file, say what was written; exit status.

    A progress bar of the frames on stderr unless ``quiet``.
    """
    from tqdm import tqdm

    bar = None if quiet else tqdm(desc="export", unit="frame", leave=False, file=sys.stderr)

    def step(done: int, total: int) -> None:
        assert bar is not None
        bar.total = total
        bar.update(done - bar.n)

    try:
        result = export_replay(log, out, name=name, progress=None if bar is None else step)
    finally:
        if bar is not None:
            bar.close()
    print(f"wrote {result.path}: {result.size / 1e6:.1f} MB, {result.duration:.1f} s of flight "
          f"at {result.rate_hz:g} frames/s, in {result.seconds:.1f} s; open it in a browser "
          "(no server, no network)", flush=True)
    return 0
