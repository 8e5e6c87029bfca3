"""The status panel as HTML: flight phase, operator command, vehicles, links, events.

Plain functions from the loop's snapshot (and the link health) to HTML strings,
so what the operator reads can be tested without a browser. Elements carry
``data-gcs`` attributes naming what they show, for tests and for scripts.
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from gcs.config import Team
from gcs.link import LinkHealth
from gcs.loop import Deformation, FleetState, RuntimeSnapshot, TickStats
from gcs.wire import SimTruth
from web._events import EventLike, EventLine, bursts, conditions
from web._frame import rope_pull_estimate, vehicle_states
from web.palette import VehicleState, state_colors, tension_colors

__all__ = ["EVENT_LOG_LINES", "UiStats", "event_filter_html", "events_html", "position_sources",
           "prearm_banner_html", "rope_legend", "safety_banner_html", "summary_html",
           "vehicle_table_html", "vehicles_html"]

EVENT_LOG_LINES = 400
"""Lines the events log holds (it scrolls); older ones are counted in the conditions."""

_LEVEL_COLOR = {"info": "#455a64", "warning": "#e67e22", "error": "#c0392b"}
_CELL = "padding:1px 3px;text-align:right;white-space:nowrap"
_HEAD = "padding:1px 3px;text-align:right;font-weight:500;color:#607d8b;vertical-align:bottom"
"""Header cells may wrap ("batt" over "%"): the tables then fit the 470 px status panel,
their last columns included, without scrolling sideways."""
_BANNER = ("font-weight:bold;padding:3px 8px;margin:2px 0;border-radius:3px;"
           "color:#fff;background:")


@dataclass(frozen=True)
class UiStats:
    """How the UI keeps up: frames per second and the server-side cost of a frame."""

    rate_hz: float
    draw_ms: float  # median over the recent frames
    draw_p99_ms: float


def _num(x: float, fmt: str, unit: str = "") -> str:
    """``x`` formatted, "–" when unknown; never "-0.00" for a value that rounds to zero."""
    if x is None or not math.isfinite(x):
        return "–"
    text = f"{x:{fmt}}"
    if text.startswith("-") and float(text) == 0.0:
        text = text[1:]
    return f"{text}{unit}"


def _payload_text(truth: SimTruth | None) -> str:
    if truth is None:
        return "not measured (drawn where taut ropes would hold it)"
    x, y, z = truth.payload_p_ned
    return (f"{_num(-z, '.2f')} m up at ({_num(x, '.2f')}, {_num(y, '.2f')}) m, speed "
            f"{math.hypot(*truth.payload_v_ned):.2f} m/s (simulator)")


def _truth_covers(truth: SimTruth | None, ids: tuple[int, ...]) -> bool:
    """True when the simulator's truth measures every vehicle's rope (the scene's rule)."""
    return truth is not None and set(truth.ids) >= set(ids)


def _swatch(rgb: np.ndarray) -> str:
    r, g, b = (int(c) for c in rgb)
    return f'<span style="color:rgb({r},{g},{b})">&#9644;</span>'


def rope_legend(measured: bool) -> str:
    """What the ropes' colours mean: the simulator's tension, or the pull estimated from tilt."""
    slack, nominal, double = tension_colors(np.array([0.0, 1.0, 2.0]), 1.0)
    if measured:
        what, scale = "tension (simulator)", "equilibrium"
    else:
        what, scale = ("horizontal pull estimated from tilt (no simulator: a lower bound, "
                       "meaningful in steady flight)", "nominal (eq. Th)")
    return (f'<span data-gcs="ropes" title="rope colours">{what}: {_swatch(slack)} slack '
            f'{_swatch(nominal)} {scale} {_swatch(double)} twice, '
            f'{_swatch(tension_colors(np.array([np.nan]), 1.0)[0])} unknown</span>')


def summary_html(snap: RuntimeSnapshot | None, *, loop: TickStats | None, control: str,
                 ui: UiStats | None, unsigned: Sequence[int] = ()) -> str:
    """Phase, operator command, control holder, payload, safety verdict and loop timing;
    ``unsigned``: vehicles whose link is not signed (a red banner)."""
    if snap is None:
        return '<div style="padding:4px 8px">waiting for the first guidance tick…</div>'
    op = snap.operator
    d = op.demand
    command = (f"fwd {d.forward:+.2f} · right {d.right:+.2f} · rot {d.rotate:+.2f} · "
               f"scale {d.scale:.2f} → {op.scale_target:.2f} · "
               f"alt {op.altitude:.2f} → {op.altitude_target:.2f} m · "
               f"guidance {'on' if op.guidance_on else 'off'} · from {html.escape(op.source)}")
    timing = "" if loop is None else (
        f"loop {loop.ticks} ticks · compute p99 {1e3 * loop.compute_p99:.1f} ms · "
        f"jitter p99 {1e3 * loop.jitter_p99:.0f} ms · overruns {loop.overruns} · "
        f"longest stall {loop.stall_max:.2f} s · longest setpoint gap "
        f"{loop.setpoint_gap_max:.2f} s")
    ui_text = "" if ui is None else (f' · UI <span data-gcs="ui-rate">{ui.rate_hz:.1f}</span> Hz, '
                                     f"frame {ui.draw_ms:.2f} ms (p99 {ui.draw_p99_ms:.2f})")
    worst = np.nanmax(np.abs(snap.distance_errors)) if np.isfinite(snap.distance_errors).any() \
        else math.nan
    return (
        '<div style="padding:2px 8px;font-size:0.85em;line-height:1.5">'
        f'{safety_banner_html(snap)}{signing_banner_html(unsigned)}{banners_html(snap)}'
        f'{prearm_banner_html(snap)}'
        f'<div>phase <b data-gcs="phase" style="font-size:1.2em">{snap.phase.text}</b>'
        f' · worst distance error '
        f'<span data-gcs="worst-error">{_num(worst, ".3f", " m")}</span></div>'
        f'<div>command <span data-gcs="operator">{command}</span></div>'
        f'<div>control <span data-gcs="control">{html.escape(control)}</span></div>'
        f'<div>payload <span data-gcs="payload">{_payload_text(snap.truth)}</span></div>'
        f'<div>ropes {rope_legend(_truth_covers(snap.truth, snap.fleet.ids))}</div>'
        f'<div style="color:#78909c">{timing}{ui_text}</div>'
        '</div>')


def safety_banner_html(snap: RuntimeSnapshot) -> str:
    """The safety rules' verdict as a banner, always there: ok (green, slim), motion frozen
    (orange), landing the team (red), each with its reasons and the vehicles they cover;
    a held team has its own banner (:func:`banners_html`)."""
    verdict = snap.safety
    covered: dict[str, set[int]] = {}
    for e in verdict.events:
        covered.setdefault(e.reason.value, set()).add(e.vehicle)
    reasons = "; ".join(EventLine(t=0.0, first_t=0.0, level="", text=reason, count=1,
                                  vehicles=tuple(sorted(ids))).describe()
                        for reason, ids in covered.items())
    if verdict.land:
        state, colour, text = "landing", "#c0392b", "LANDING THE TEAM"
    elif verdict.hold:
        return ""
    elif verdict.freeze and not verdict.events:
        state, colour, text = "waiting", "#78909c", "WAITING FOR EVERY VEHICLE: motion frozen"
    elif verdict.freeze:
        state, colour, text = "frozen", "#e67e22", "MOTION FROZEN"
    else:
        return (f'<div data-gcs-banner="safety" data-gcs-safety="ok" style="{_BANNER}#27ae60;'
                f'padding:1px 8px;font-size:0.9em">SAFETY OK</div>')
    if reasons:
        text = f"{text}: {reasons}"
    return (f'<div data-gcs-banner="safety" data-gcs-safety="{state}" '
            f'style="{_BANNER}{colour}">{html.escape(text)}</div>')


def signing_banner_html(unsigned: Sequence[int]) -> str:
    """A red banner while any vehicle's link is unsigned: anyone who reaches its port or
    radio commands it (``--insecure``, or a real autopilot without the team key)."""
    if not unsigned:
        return ""
    ids = ", ".join(str(v) for v in unsigned)
    text = (f"UNSIGNED LINK{'S' if len(unsigned) > 1 else ''}: vehicle"
            f"{'s' if len(unsigned) > 1 else ''} {ids} obey{'' if len(unsigned) > 1 else 's'} "
            f"anyone who reaches {'their' if len(unsigned) > 1 else 'its'} link (MAVLink "
            f"signing off; see gcs key)")
    return (f'<div data-gcs-banner="signing" style="background:#c0392b;color:#fff;'
            f'font-weight:bold;padding:3px 8px;margin:2px 0;border-radius:3px">'
            f"{html.escape(text)}</div>")


def banners_html(snap: RuntimeSnapshot) -> str:
    """What the operator must see at once, one banner each: vehicles waiting to be flown
    again (and whether to press Resume), a held team, the geofence."""
    out = []
    if snap.recovery:
        colour = "#e67e22" if "re-engaging" in snap.recovery or "waiting" in snap.recovery \
            else "#c0392b"
        out.append((colour, "recovery", snap.recovery))
    if snap.shape is Deformation.REFORM:
        out.append(("#e67e22", "hold", "RE-FORMING: the team is deformed beyond the "
                    "analysis' safe bound; shape keeping with the motion frozen"))
    elif snap.safety.hold:
        out.append(("#c0392b", "hold", "HOLDING: the team is deformed beyond the analysis' "
                    "safe bound; each vehicle holds its point (land if it grows)"))
    if snap.fence is not None and snap.fence.text:
        out.append(("#e67e22", "fence", snap.fence.text))
    return "".join(
        f'<div data-gcs-banner="{key}" style="background:{colour};color:#fff;'
        f'font-weight:bold;padding:3px 8px;margin:2px 0;border-radius:3px">'
        f"{html.escape(text)}</div>" for colour, key, text in out)


def prearm_banner_html(snap: RuntimeSnapshot) -> str:
    """While the team is ready: the checks before arming that fail now, one line each
    naming the vehicle (:meth:`gcs.loop.Prearm.watch`), so the operator sees them before
    pressing ARM, which would refuse; nothing when they pass."""
    if not snap.prearm:
        return ""
    lines = "".join(f'<div data-gcs="prearm-check" style="font-weight:normal">'
                    f"{html.escape(text)}</div>" for text in snap.prearm)
    return (f'<div data-gcs-banner="prearm" style="{_BANNER}#e67e22">ARM WOULD BE REFUSED: '
            f"{len(snap.prearm)} check{'s' if len(snap.prearm) > 1 else ''} before arming "
            f"fail{'' if len(snap.prearm) > 1 else 's'}{lines}</div>")


_SOURCES = {"shared": "local NED (shared)", "set_origin": "local NED (origin set by GCS)",
            "global": "local NED + GPS origin"}


def position_sources(team: Team) -> dict[int, str]:
    """Where each vehicle's position comes from, as the team file's ``team_frame`` says:
    ``auto`` is the simulator's shared frame on simulated links, the GPS origin on others.

    Read with ``getattr``: a team file's ``team_frame`` section is newer than this page,
    and without it the frame is the simulator's shared one.
    """
    frame = getattr(team.config, "team_frame", None)
    mode = str(getattr(frame, "mode", "shared"))
    links = {link.sysid: link for link in team.config.vehicle_links()}
    out = {}
    for vid in team.formation.ids:
        own = mode
        if mode == "auto":
            link = links.get(vid)
            own = "shared" if link is None or link.profile == "sim" else "global"
        out[vid] = _SOURCES.get(own, own)
    return out


def vehicles_html(snap: RuntimeSnapshot | None, *, health: Mapping[int, LinkHealth],
                  truth: SimTruth | None, mass: float, stale_after: float,
                  voltage: np.ndarray | None = None, quality: Mapping[int, float] | None = None,
                  sources: Mapping[int, str] | None = None) -> str:
    """The vehicles' tables (:func:`vehicle_table_html`) from the loop's snapshot."""
    if snap is None:
        return ""
    f = snap.fleet
    measured = _truth_covers(truth, f.ids)
    rope = np.array([truth.rope_tension[truth.ids.index(vid)] for vid in f.ids]) \
        if measured and truth else rope_pull_estimate(mass, f.tilt, snap.accel_cmd)
    rope_head = "rope N (sim)" if measured else (
        '<span title="horizontal rope pull estimated from tilt (a lower bound)">'
        "rope pull ≈ N</span>")
    return vehicle_table_html(f, stale_after=stale_after, rope=rope, rope_head=rope_head,
                              health=health, voltage=voltage, quality=quality, sources=sources)


def _table(key: str, head: Sequence[str], rows: Sequence[tuple[int, Sequence[str]]]) -> str:
    header = "".join(f'<th style="{_HEAD}">{h}</th>' for h in head)
    body = "".join(f'<tr data-gcs="{key}-{vid}">' +
                   "".join(f'<td style="{_CELL}">{c}</td>' for c in cells) + "</tr>"
                   for vid, cells in rows)
    return (f'<table data-gcs="{key}s" style="border-collapse:collapse;font-size:0.8em;'
            f'margin-bottom:3px"><tr>{header}</tr>{body}</table>')


def vehicle_table_html(f: FleetState, *, stale_after: float, rope: np.ndarray, rope_head: str,
                       health: Mapping[int, LinkHealth],
                       heartbeat_age: np.ndarray | None = None,
                       voltage: np.ndarray | None = None,
                       quality: Mapping[int, float] | None = None,
                       sources: Mapping[int, str] | None = None) -> str:
    """Two tables, one row per vehicle in each: what it is doing, then its link.

    Vehicles (rows ``vehicle-<id>``): state, mode, armed, battery % and volts,
    altitude, tilt, heartbeat age, position age (stale past ``stale_after``),
    rope. Links (rows ``link-<id>``): quality % (``quality``, frames received
    of those sent over the last seconds), frames lost, refused, round trip,
    position source. The replay draws the live tables from a log: it has no
    links, so the recorded ``heartbeat_age`` stands in for the link's and the
    link's counters show as unknown.
    """
    states = vehicle_states(f, stale_after)
    colors = state_colors(states)
    quality = quality or {}
    sources = sources or {}
    volts = voltage if voltage is not None else np.full(f.n, math.nan)
    flight, links = [], []
    for i, vid in enumerate(f.ids):
        h = health.get(vid)
        hb = h.heartbeat_age_s if h and h.heartbeat_age_s is not None else (
            float(heartbeat_age[i]) if h is None and heartbeat_age is not None else math.nan)
        r, g, b = (int(c) for c in colors[i])
        age = float(f.age[i])
        stale = not (math.isfinite(age) and age <= stale_after)
        flight.append((vid, (
            f'<b>{vid}</b>',
            f'<span style="color:rgb({r},{g},{b})">&#9679;</span> '
            f'{VehicleState(states[i]).text}',
            html.escape(f.modes[i]),
            "yes" if f.armed[i] else "no",
            _num(float(f.battery[i]), ".0f"),
            _num(float(volts[i]), ".1f"),
            _num(-float(f.p_ned[i, 2]), ".2f"),
            _num(math.degrees(float(f.tilt[i])), ".1f"),
            _num(hb, ".1f"),
            f'<span style="color:#c0392b">{_num(age, ".1f")}</span>' if stale
            else _num(age, ".2f"),
            _num(float(rope[i]), ".2f"),
        )))
        links.append((vid, (
            f'<b>{vid}</b>',
            _num(quality.get(vid, math.nan), ".0f"),
            str(h.packets_lost) if h else "–",
            str(h.refused) if h else "–",
            _num(1e3 * h.rtt_s if h and h.rtt_s is not None else math.nan, ".0f"),
            html.escape(sources.get(vid, "–")),
        )))
    return ('<div data-gcs="vehicles" style="overflow-x:auto;padding:0 4px">'
            + _table("vehicle", ("id", "state", "mode", "armed", "batt %", "batt V", "alt m",
                                 "tilt °", "hb s", "pos s", rope_head), flight)
            + _table("link", ("id", "link %", "lost", "refused", "rtt ms", "position source"),
                     links)
            + "</div>")


def event_filter_html() -> str:
    """The events' level filter: radio buttons and the style that hides the lines below the
    level chosen, in the page itself (each viewer its own, with no message to the server).

    A separate element that never changes, so the choice survives the events' updates
    (viser replaces an HTML element's whole content when it changes).
    """
    hide = {"warning": ("info",), "error": ("info", "warning")}
    rules = "".join(
        f"body:has([data-gcs=event-filter] input[value={level}]:checked) "
        f"[data-gcs=event-log] :is({', '.join(f'[data-level={h}]' for h in hidden)})"
        "{display:none}" for level, hidden in hide.items())
    choices = "".join(
        f'<label style="margin-right:8px;white-space:nowrap"><input type="radio" '
        f'name="gcs-event-level" value="{value}"{" checked" if value == "info" else ""}> '
        f"{text}</label>"
        for value, text in (("info", "all"), ("warning", "warnings and errors"),
                            ("error", "errors")))
    return (f'<style>{rules}</style><div data-gcs="event-filter" '
            f'style="padding:2px 8px;font-size:0.8em;color:#607d8b">log shows {choices}</div>')


def _event_line(t: float, level: str, text: str, start: float) -> str:
    return (f'<div data-level="{level}"><div style="color:{_LEVEL_COLOR.get(level, "#455a64")}">'
            f'<span style="color:#90a4ae">{t - start:7.1f} s</span> {html.escape(text)}'
            "</div></div>")


def events_html(events: Sequence[EventLike], *, start: float = 0.0, window: float = 1.0) -> str:
    """What happened, as an operator reads it (:mod:`web._events`).

    On top, one line per warning or error condition, latest first, with its
    count and the vehicles it covered (``data-gcs="conditions"``); below, the
    log, newest first, one line per burst of one condition within ``window`` s,
    scrolling, each line tagged with its level for :func:`event_filter_html`.
    Times are shown from ``start``, s.
    """
    if not events:
        return ('<div data-gcs="events" style="padding:2px 8px;color:#90a4ae;font-size:0.8em">'
                "no events yet</div>")
    now = conditions(events)
    top = "".join(_event_line(c.t, c.level, c.describe(), start) for c in now) \
        or '<div style="color:#27ae60">no warnings</div>'
    log = "".join(_event_line(b.first_t, b.level, b.describe(), start)
                  for b in reversed(bursts(events, window=window)[-EVENT_LOG_LINES:]))
    return ('<div data-gcs="events" style="padding:2px 8px;font-size:0.8em;line-height:1.4">'
            f'<div data-gcs="conditions" style="margin-bottom:4px">{top}</div>'
            '<div data-gcs="event-log" style="max-height:260px;overflow-y:auto;'
            f'border-top:1px solid #eceff1;padding-top:2px">{log}</div></div>')
