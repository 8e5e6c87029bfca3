"""``gcs report``: figures and a summary of a recorded flight.

Each figure is written as SVG and as a 200 dpi PNG (``formation.svg`` and
``formation.png``, ...):

* ``formation``: inter-vehicle distances against their desired values (top)
  and x/y velocities of the vehicles (bottom), like the paper's experimental figure;
  for a plain autopilot log (no team, no guidance ticks) the distances between
  the vehicles' own positions, without desired values;
* ``trajectories``: top view of the vehicles' (and the payload's) paths,
  like the paper's trajectory plot;
* ``distance_errors``: the distance error of every edge;
* ``accelerations``: commanded accelerations against the limits: the norm
  against the norm limit (top), each axis against the per-axis limit (bottom);
* ``summary.json`` and ``summary.md``: duration, worst distance error overall and
  per phase, worst swing, worst bank, rope tensions, link losses of what the
  vehicles sent (per system and component), phases, events (one line per
  condition, :func:`event_lines`), what the log does not contain and how much of
  it could not be read.

How the figures look (a colour per vehicle, the phase key, legends beside the
axes, limits) is :mod:`gcs.flightlog._figstyle`. The summary's metrics come from
:meth:`FlightLog.metrics`, the same code that ``gcs fly`` runs live, so both
agree for the same flight; a log without guidance ticks gets what its telemetry
gives (:meth:`FlightLog.telemetry_metrics`).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.artist import Artist
from matplotlib.lines import Line2D

from gcs.flightlog._events import event_lines, id_ranges
from gcs.flightlog._figstyle import (
    axis_styles,
    edge_colours,
    legend_outside,
    mark_limit,
    phase_key,
    save_figure,
    shade_phases,
    vehicle_colours,
)
from gcs.flightlog._flight import FlightLog

__all__ = ["FIGURES", "PAIRS_DRAWN", "PLOT_BUCKETS", "envelope", "vehicle_distances",
           "write_report"]

PLOT_BUCKETS = 2000
"""Time buckets per plotted series: about two per pixel of a figure 10 inches wide."""

FIGURES = ("formation", "trajectories", "distance_errors", "accelerations")
"""Every figure a report can hold, in order, each written as ``NAME.svg`` and ``NAME.png``;
a log lacking what one needs goes without it."""

PAIRS_DRAWN = 8
"""Up to this many vehicles, a plain log's figure draws every pair's distance; beyond,
only the closest pair's (28 lines are already hard to tell apart)."""


def envelope(y: np.ndarray, buckets: int = PLOT_BUCKETS) -> np.ndarray:
    """Indices of ``y`` that keep each time bucket's lowest and highest sample, in order.

    Why: a figure cannot show more than a few points per pixel, while an hour of
    telemetry is hundreds of thousands of samples per line, which matplotlib
    turns into paths of hundreds of megabytes. Keeping each bucket's extremes
    (not every k-th sample) still draws every spike, which is what a report
    of a flight is read for.
    """
    n = len(y)
    if n <= 2 * buckets:
        return np.arange(n)
    size = -(-n // buckets)
    flat = np.full(size * buckets, np.nan)
    flat[:n] = y
    grid = flat.reshape(buckets, size)
    finite = np.isfinite(grid)
    base = np.arange(buckets) * size
    lo = base + np.where(finite, grid, np.inf).argmin(axis=1)
    hi = base + np.where(finite, grid, -np.inf).argmax(axis=1)
    keep = np.unique(np.concatenate([lo, hi]))
    return keep[keep < n]


def _plot(ax: plt.Axes, t: np.ndarray, y: np.ndarray, *args: Any, **kwargs: Any) -> list:
    """``ax.plot(t, y, ...)`` of a time series, thinned by :func:`envelope`."""
    keep = envelope(y)
    return ax.plot(t[keep], y[keep], *args, **kwargs)


def _path(ax: plt.Axes, x: np.ndarray, y: np.ndarray, *args: Any, **kwargs: Any) -> list:
    """``ax.plot(x, y, ...)`` of a path, every k-th point (paths are smooth) plus the last."""
    keep = np.unique(np.r_[np.arange(0, len(x), max(1, len(x) // (4 * PLOT_BUCKETS))),
                           len(x) - 1]) if len(x) else np.zeros(0, dtype=int)
    return ax.plot(x[keep], y[keep], *args, **kwargs)


def write_report(log: FlightLog, out: Path,
                 progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Write the figures and summaries of ``log`` into ``out``; returns the summary."""
    out.mkdir(parents=True, exist_ok=True)
    files: list[str] = []
    draw = (_formation, _trajectories, _distance_errors, _accelerations)
    for stem, fn in zip(FIGURES, draw, strict=True):
        if progress is not None:
            progress(stem)
        fig = fn(log)
        if fig is None:
            continue
        try:
            files += save_figure(fig, out, stem)
        finally:
            plt.close(fig)
    summary = _summary(log, files)
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    (out / "summary.md").write_text(_markdown(summary))
    return summary


def _t0(log: FlightLog) -> float:
    starts = [log.tick_t[0]] if len(log.tick_t) else []
    starts += [tr.t[0] for tr in log.tracks.values() if len(tr.t)]
    return min(starts) if starts else 0.0


def _shade(ax: plt.Axes, log: FlightLog, t0: float) -> list[str]:
    """The payload phases shaded on a time plot (none in a log without guidance ticks)."""
    if not len(log.tick_t):
        return []
    return shade_phases(ax, log.phase_changes(), float(log.tick_t[-1]), t0)


def _colours(log: FlightLog) -> dict[int, tuple[float, float, float, float]]:
    """Each vehicle's colour, the same in every figure of the report."""
    ids = set(log.tracks) | (set(log.team["ids"]) if log.team is not None else set())
    return vehicle_colours(ids)


def _vehicle_handles(colours: dict[int, tuple[float, float, float, float]],
                     ids: Iterable[int]) -> list[Artist]:
    return [Line2D([], [], color=colours[vid], lw=1.5, label=f"vehicle {vid}")
            for vid in sorted(ids)]


def _formation(log: FlightLog) -> plt.Figure | None:
    if not log.tracks:
        return None
    t0 = _t0(log)
    colours = _colours(log)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 7), sharex=True, layout="constrained")
    desired_drawn = log.team is not None and "dist_err" in log.arrays and len(log.tick_t) > 0
    shaded = []
    if desired_drawn:
        assert log.team is not None  # desired_drawn says so
        d = np.asarray(log.team["distances"])
        scale = log.values.get("scale", np.ones(len(log.tick_t)))
        desired = scale[:, None] * d[None, :]
        actual = desired + log.arrays["dist_err"][:, : len(d)]
        ids = log.team["ids"]
        edges = log.team["edges"]
        t = log.tick_t - t0
        for k, colour in enumerate(edge_colours(len(d))):
            i, j = edges[k]
            _plot(top, t, actual[:, k], lw=1.2, color=colour, label=f"{ids[i]}-{ids[j]}")
        handles: list[Artist] = list(top.get_lines())
        for value in np.unique(np.round(desired, 3), axis=1).T:
            _plot(top, t, value, "k--", lw=0.8, label="_desired")
        handles.append(Line2D([], [], color="k", ls="--", lw=0.8, label="desired"))
        legend_outside(top, handles, title="edge")
        shaded = _shade(top, log, t0)
    elif (pairs := vehicle_distances(log)) is not None:
        t, distances = pairs
        for ((a, b), d), colour in zip(distances.items(), edge_colours(len(distances)),
                                       strict=True):
            _plot(top, t - t0, d, lw=1.2, color=colour,
                  label=f"{a}-{b}" if b else f"closest ({a} vehicles)")
        legend_outside(top, top.get_lines(), title="pair")
        top.set_title("between the vehicles' positions (no desired values: no team header)",
                      fontsize=9)
    else:
        top.text(0.5, 0.5, "distances: fewer than two vehicles with positions in this log",
                 ha="center", va="center", transform=top.transAxes)
    top.set_ylabel("distance [m]")
    for sysid, tr in sorted(log.tracks.items()):
        _plot(bottom, tr.t - t0, tr.v_ned[:, 0], lw=1, color=colours[sysid],
              label=f"vehicle {sysid} x")
        _plot(bottom, tr.t - t0, tr.v_ned[:, 1], lw=1, ls=":", color=colours[sysid],
              label=f"vehicle {sysid} y")
    _shade(bottom, log, t0)
    bottom.axhline(0, color="k", lw=0.5, label="_zero")
    bottom.set_ylabel("velocity [m/s]")
    bottom.set_xlabel("time [s]")
    legend_outside(bottom, _vehicle_handles(colours, log.tracks) + axis_styles())
    phase_key(fig, shaded)
    fig.suptitle("Distances (desired dashed) and velocities" if desired_drawn
                 else "Distances and velocities")
    return fig


def vehicle_distances(log: FlightLog, samples: int = 8 * PLOT_BUCKETS
                      ) -> tuple[np.ndarray, dict[tuple[int, int], np.ndarray]] | None:
    """Distances between the vehicles over time, from their own positions (no team needed).

    Sampled at the recorded position times (every k-th of them past ``samples``),
    each vehicle at its latest position at or before (NaN before its first), as
    the replay draws them. Every pair up to :data:`PAIRS_DRAWN` vehicles, keyed by
    their ids; beyond, one series keyed (vehicles, 0): the closest pair's distance.
    None with fewer than two vehicles that have positions.
    """
    tracks = {s: tr for s, tr in sorted(log.tracks.items()) if len(tr.t)}
    if len(tracks) < 2:
        return None
    t = np.unique(np.concatenate([tr.t for tr in tracks.values()]))
    t = t[:: max(1, -(-len(t) // samples))]
    p = np.full((len(tracks), len(t), 3), np.nan)
    for i, tr in enumerate(tracks.values()):
        k = np.searchsorted(tr.t, t, side="right") - 1
        p[i, k >= 0] = tr.p_ned[k[k >= 0]]
    ids = list(tracks)
    pairs = [(i, j) for i in range(len(ids)) for j in range(i + 1, len(ids))]
    if len(ids) <= PAIRS_DRAWN:
        return t, {(ids[i], ids[j]): np.linalg.norm(p[i] - p[j], axis=1) for i, j in pairs}
    closest = np.full(len(t), np.inf)
    for i, j in pairs:
        closest = np.fmin(closest, np.linalg.norm(p[i] - p[j], axis=1))
    return t, {(len(ids), 0): np.where(np.isfinite(closest), closest, np.nan)}


def _trajectories(log: FlightLog) -> plt.Figure | None:
    if not log.tracks:
        return None
    colours = _colours(log)
    fig, ax = plt.subplots(figsize=(8, 7), layout="constrained")
    handles: list[Artist] = []
    for sysid, tr in sorted(log.tracks.items()):
        if not len(tr.t):
            continue
        handles += _path(ax, tr.p_ned[:, 1], tr.p_ned[:, 0], lw=1, color=colours[sysid],
                         label=f"vehicle {sysid}")
        ax.plot(tr.p_ned[-1, 1], tr.p_ned[-1, 0], "o", ms=4, color=colours[sysid],
                label=f"_vehicle {sysid} end")
    if "payload" in log.arrays:
        p = log.arrays["payload"]
        handles += _path(ax, p[:, 1], p[:, 0], "k-", lw=1.5, label="payload")
    if handles:
        handles.append(Line2D([], [], color="0.3", ls="", marker="o", ms=4, label="end"))
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(alpha=0.3)
    legend_outside(ax, handles)
    ax.set_title("Trajectories (top view)")
    return fig


def _distance_errors(log: FlightLog) -> plt.Figure | None:
    if "dist_err" not in log.arrays or log.team is None:
        return None
    t0 = _t0(log)
    fig, ax = plt.subplots(figsize=(10, 4), layout="constrained")
    e = log.arrays["dist_err"]
    ids, edges = log.team["ids"], log.team["edges"]
    for k, colour in enumerate(edge_colours(e.shape[1])):
        i, j = edges[k]
        _plot(ax, log.tick_t - t0, e[:, k], lw=1, color=colour, label=f"{ids[i]}-{ids[j]}")
    legend_outside(ax, ax.get_lines(), title="edge")
    phase_key(fig, _shade(ax, log, t0))
    ax.axhline(0, color="k", lw=0.5, label="_zero")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("distance error e_k [m]")
    ax.set_title("Distance error per edge")
    return fig


def _accelerations(log: FlightLog) -> plt.Figure | None:
    if "acc_cmd" not in log.arrays or not len(log.tick_t):
        return None
    t0 = _t0(log)
    t = log.tick_t - t0
    acc = log.per_vehicle("acc_cmd", 2)
    ids = log.team["ids"] if log.team is not None else tuple(range(1, log.n_vehicles + 1))
    colours = vehicle_colours(set(ids) | set(log.tracks))
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 6), sharex=True, layout="constrained")
    for i, vid in enumerate(ids):
        _plot(top, t, np.linalg.norm(acc[:, i], axis=1), lw=1, color=colours[vid],
              label=f"vehicle {vid} |a|")
        _plot(bottom, t, acc[:, i, 0], lw=1, color=colours[vid], label=f"vehicle {vid} x")
        _plot(bottom, t, acc[:, i, 1], lw=1, ls=":", color=colours[vid],
              label=f"vehicle {vid} y")
    top_handles = _vehicle_handles(colours, ids)
    bottom_handles = axis_styles()
    if log.team is not None:
        with np.errstate(invalid="ignore"):
            peak_norm = float(np.nanmax(np.linalg.norm(acc, axis=2), initial=0.0))
            peak_axis = float(np.nanmax(np.abs(acc), initial=0.0))
        line = mark_limit(top, float(log.team["accel_norm"]), peak_norm,
                          label="norm limit", unit="m/s^2", colour="r")
        top_handles += [line] if line is not None else []
        line = mark_limit(bottom, float(log.team["accel_axis"]), peak_axis,
                          label="per-axis limit", unit="m/s^2", colour="m",
                          symmetric=True)
        bottom_handles += [line] if line is not None else []
    shaded = _shade(top, log, t0)
    _shade(bottom, log, t0)
    bottom.axhline(0, color="k", lw=0.5, label="_zero")
    top.set_ylabel("|a| [m/s^2]")
    bottom.set_ylabel("a per axis [m/s^2]")
    bottom.set_xlabel("time [s]")
    legend_outside(top, top_handles)
    legend_outside(bottom, bottom_handles)
    phase_key(fig, shaded)
    fig.suptitle("Commanded horizontal accelerations against the limits")
    return fig


def _summary(log: FlightLog, figures: list[str]) -> dict[str, Any]:
    metrics = log.metrics().to_json() if len(log.tick_t) else log.telemetry_metrics()
    t0 = _t0(log)
    return {
        "log": str(log.index.path),
        "messages": len(log.index),
        "corrupt_bytes_skipped": log.index.skipped_bytes,
        "unknown_frames_skipped": log.index.unknown_frames,
        "bad_timestamps_rejected": log.index.rejected_times,
        "truncated": log.index.truncated,
        "damage": log.index.damage(),
        "cut_short": log.cut_short(),
        "vehicles": sorted(log.tracks),
        "metrics": metrics,
        "link_losses": {f"{s}/{c}": n for (s, c), n in sorted(log.link_losses().items())},
        "phases": [{"t_s": round(t - t0, 2), "phase": p} for t, p in log.phase_changes()],
        "events": [{"t_s": round(t - t0, 2), "system": s, "severity": sev, "text": txt}
                   for t, s, sev, txt in log.texts],
        "event_lines": [line.to_json() for line in event_lines(
            (x for x in log.texts if not _phase_text(log, x)), t0, log.tracks)],
        "missing": log.missing,
        "figures": figures,
    }


def _phase_text(log: FlightLog, text: tuple[float, int, int, str]) -> bool:
    """A ground station's ``phase: ...`` text: the phases have their own list."""
    return text[1] in log.ground and text[3].startswith("phase: ")


def _markdown(s: dict[str, Any]) -> str:
    m = s["metrics"] or {}
    lines = [f"# Flight report: {Path(str(s['log'])).name}", ""]
    if s["cut_short"]:
        lines += [f"**This flight was {s['cut_short']}** (the GCS stopped or was killed, "
                  "or the log was cut): the figures cover only what was recorded.", ""]
    if m:
        lines += ["| metric | value |", "|---|---|"]
        for key in ("duration_s", "worst_distance_error_m", "payload_lift_m", "worst_swing_rad",
                    "worst_bank_rad", "worst_accel_cmd_m_s2", "rope_tension_min_N",
                    "rope_tension_max_N"):
            value = m.get(key)
            lines.append(f"| {key} | {'not in this log' if value is None else value} |")
        by_phase = m.get("worst_distance_error_by_phase_m") or {}
        if by_phase:
            lines += ["", "Worst distance error per phase (m):", ""]
            lines += [f"- {phase}: {value}" for phase, value in by_phase.items()]
    lines += ["", "Link losses (frames the vehicles sent missing from the log by sequence "
                  "number, per system/component; in a damaged log the unreadable ones count "
                  f"too): {s['link_losses']}", "",
              f"Damaged log: {s['damage']}" if s["damage"] else "Read whole: nothing "
              "truncated, skipped or rejected.", ""]
    if s["missing"]:
        lines += ["Not in this log:", ""] + [f"- {x}" for x in s["missing"]] + [""]
    if s["phases"]:
        lines += ["## Phases", "", ", ".join(f"{p['phase']} at {p['t_s']} s"
                                             for p in s["phases"]), ""]
    lines += ["## Events", ""] + _event_table(s["event_lines"])
    lines += ["", "Figures: " + ", ".join(s["figures"])]
    return "\n".join(lines) + "\n"


def _event_table(rows: list[dict[str, Any]]) -> list[str]:
    """One row per condition: when first, level, how often, which vehicles, what."""
    if not rows:
        return ["None logged."]
    table = ["One row per condition: `count` is how often it was logged in all (once per "
             "vehicle it covers, each time it happened), `first [s]` when first.", "",
             "| first [s] | level | count | vehicles | event |", "|---:|---|---:|---|---|"]
    for row in rows:
        text = str(row["text"]).replace("|", "\\|")
        table.append(f"| {row['first_s']} | {row['level']} | {row['count']} | "
                     f"{id_ranges(row['vehicles']) or '-'} | {text} |")
    return table
