"""The status panel as HTML: flight phase, operator command, vehicles, links, events.

Plain functions from the loop's snapshot (and the link health) to HTML strings,
so what the operator reads can be tested without a browser. Elements carry
``data-gcs`` attributes naming what they show, for tests and for scripts.
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from gcs.link import LinkHealth
from gcs.loop import Deformation, FleetState, RuntimeSnapshot, TickStats
from gcs.wire import SimTruth
from web._frame import rope_pull_estimate, vehicle_states
from web.palette import VehicleState, state_colors, tension_colors

__all__ = ["UiStats", "events_html", "rope_legend", "summary_html",
           "vehicle_table_html", "vehicles_html"]

_LEVEL_COLOR = {"info": "#455a64", "warning": "#e67e22", "error": "#c0392b"}
_CELL = "padding:1px 4px;text-align:right;white-space:nowrap"
_HEAD = "padding:1px 4px;text-align:right;font-weight:500;color:#607d8b;vertical-align:bottom"
"""Header cells may wrap ("batt" over "%"): the table then fits the 470 px status panel,
its last column (rtt) included, without scrolling sideways."""


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
                 ui: UiStats | None) -> str:
    """Phase, operator command, control holder, payload, safety verdict and loop timing."""
    if snap is None:
        return '<div style="padding:4px 8px">waiting for the first guidance tick…</div>'
    op = snap.operator
    d = op.demand
    command = (f"fwd {d.forward:+.2f} · right {d.right:+.2f} · rot {d.rotate:+.2f} · "
               f"scale {d.scale:.2f} → {op.scale_target:.2f} · "
               f"alt {op.altitude:.2f} → {op.altitude_target:.2f} m · "
               f"guidance {'on' if op.guidance_on else 'off'} · from {html.escape(op.source)}")
    verdict = snap.safety
    if verdict.land:
        safety = '<b style="color:#c0392b">landing the team</b>'
    elif verdict.hold:
        safety = '<b style="color:#c0392b">holding: deformed beyond the safe bound</b>'
    elif verdict.freeze:
        safety = '<b style="color:#e67e22">motion frozen</b>'
    else:
        safety = '<span style="color:#27ae60">ok</span>'
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
        f'{banners_html(snap)}'
        f'<div>phase <b data-gcs="phase" style="font-size:1.2em">{snap.phase.text}</b>'
        f' · safety {safety} · worst distance error '
        f'<span data-gcs="worst-error">{_num(worst, ".3f", " m")}</span></div>'
        f'<div>command <span data-gcs="operator">{command}</span></div>'
        f'<div>control <span data-gcs="control">{html.escape(control)}</span></div>'
        f'<div>payload <span data-gcs="payload">{_payload_text(snap.truth)}</span></div>'
        f'<div>ropes {rope_legend(_truth_covers(snap.truth, snap.fleet.ids))}</div>'
        f'<div style="color:#78909c">{timing}{ui_text}</div>'
        '</div>')


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


def vehicles_html(snap: RuntimeSnapshot | None, *, health: Mapping[int, LinkHealth],
                  truth: SimTruth | None, mass: float, stale_after: float) -> str:
    """One row per vehicle: state, mode, armed, battery, tilt, rope, link health."""
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
                              health=health)


def vehicle_table_html(f: FleetState, *, stale_after: float, rope: np.ndarray, rope_head: str,
                       health: Mapping[int, LinkHealth],
                       heartbeat_age: np.ndarray | None = None) -> str:
    """The table of :func:`vehicles_html` from a fleet state and each vehicle's rope value.

    The replay draws the live table from a log: it has no links, so the
    recorded ``heartbeat_age`` stands in for the link's and the link's
    counters show as unknown.
    """
    states = vehicle_states(f, stale_after)
    colors = state_colors(states)
    head = ("id", "state", "mode", "armed", "batt %", "tilt °", "alt m", rope_head, "hb s",
            "lost", "refused", "rtt ms")
    rows = []
    for i, vid in enumerate(f.ids):
        h = health.get(vid)
        hb = h.heartbeat_age_s if h and h.heartbeat_age_s is not None else (
            float(heartbeat_age[i]) if h is None and heartbeat_age is not None else math.nan)
        r, g, b = (int(c) for c in colors[i])
        cells = (
            f'<b>{vid}</b>',
            f'<span style="color:rgb({r},{g},{b})">&#9679;</span> '
            f'{VehicleState(states[i]).text}',
            html.escape(f.modes[i]),
            "yes" if f.armed[i] else "no",
            _num(float(f.battery[i]), ".0f"),
            _num(math.degrees(float(f.tilt[i])), ".1f"),
            _num(-float(f.p_ned[i, 2]), ".2f"),
            _num(float(rope[i]), ".2f"),
            _num(hb, ".1f"),
            str(h.packets_lost) if h else "–",
            str(h.refused) if h else "–",
            _num(1e3 * h.rtt_s if h and h.rtt_s is not None else math.nan, ".0f"),
        )
        rows.append(f'<tr data-gcs="vehicle-{vid}">' +
                    "".join(f'<td style="{_CELL}">{c}</td>' for c in cells) + "</tr>")
    header = "".join(f'<th style="{_HEAD}">{h}</th>' for h in head)
    return ('<div data-gcs="vehicles" style="overflow-x:auto;padding:0 4px">'
            '<table style="border-collapse:collapse;font-size:0.8em">'
            f'<tr>{header}</tr>{"".join(rows)}</table></div>')


def events_html(snap: RuntimeSnapshot | None, *, limit: int = 8) -> str:
    """The latest phase changes, safety warnings and errors, newest first."""
    if snap is None or not snap.events:
        return '<div style="padding:2px 8px;color:#90a4ae;font-size:0.8em">no events yet</div>'
    lines = [f'<div style="color:{_LEVEL_COLOR.get(e.level, "#455a64")}">'
             f'<span style="color:#90a4ae">{e.t:7.1f} s</span> {html.escape(e.text)}</div>'
             for e in reversed(snap.events[-limit:])]
    return ('<div data-gcs="events" style="padding:2px 8px;font-size:0.8em;line-height:1.4">'
            + "".join(lines) + "</div>")
