"""``gcs report``: figures and a summary of a recorded flight.

* ``formation.png``: inter-vehicle distances against their desired values (top)
  and x/y velocities of the vehicles (bottom), like the paper's experimental figure;
  for a plain autopilot log (no team, no guidance ticks) the distances between
  the vehicles' own positions, without desired values;
* ``trajectories.png``: top view of the vehicles' (and the payload's) paths,
  like the paper's trajectory plot;
* ``distance_errors.png``: the distance error of every edge, phases shaded;
* ``accelerations.png``: commanded accelerations against the limits: the norm
  against the norm limit (top), each axis against the per-axis limit (bottom);
* ``summary.json`` and ``summary.md``: duration, worst distance error overall and
  per phase, worst swing, worst bank, rope tensions, link losses of what the
  vehicles sent (per system and component), events, what the log does not
  contain and how much of it could not be read.

The summary's metrics come from :meth:`FlightLog.metrics`, the same code that
``gcs fly`` runs live, so both agree for the same flight; a log without guidance
ticks gets what its telemetry gives (:meth:`FlightLog.telemetry_metrics`).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from gcs.flightlog._flight import FlightLog
from gcs.loop import Phase

__all__ = ["FIGURES", "PAIRS_DRAWN", "PLOT_BUCKETS", "envelope", "vehicle_distances",
           "write_report"]

PLOT_BUCKETS = 2000
"""Time buckets per plotted series: about two per pixel of a figure 10 inches wide."""

FIGURES = ("formation.png", "trajectories.png", "distance_errors.png", "accelerations.png")
"""Every figure a report can hold, in order; a log lacking what one needs goes without it."""

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
    figures = []
    draw = (_formation, _trajectories, _distance_errors, _accelerations)
    for name, fn in zip(FIGURES, draw, strict=True):
        if progress is not None:
            progress(name)
        fig = fn(log)
        if fig is None:
            continue
        fig.savefig(out / name, dpi=110)
        plt.close(fig)
        figures.append(name)
    summary = _summary(log, figures)
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    (out / "summary.md").write_text(_markdown(summary))
    return summary


def _t0(log: FlightLog) -> float:
    starts = [log.tick_t[0]] if len(log.tick_t) else []
    starts += [tr.t[0] for tr in log.tracks.values() if len(tr.t)]
    return min(starts) if starts else 0.0


def _shade_phases(ax: plt.Axes, log: FlightLog, t0: float) -> None:
    changes = log.phase_changes()
    colours = {Phase.FORMATION.text: "#e8f4e8", Phase.LIFTING.text: "#fff4dd",
               Phase.SETTING_DOWN.text: "#fff4dd", Phase.ABORTING.text: "#fde0e0"}
    for k, (t, name) in enumerate(changes):
        end = changes[k + 1][0] if k + 1 < len(changes) else log.tick_t[-1]
        if name in colours:
            ax.axvspan(t - t0, end - t0, color=colours[name], zorder=0)


def _formation(log: FlightLog) -> plt.Figure | None:
    if not log.tracks:
        return None
    t0 = _t0(log)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    desired_drawn = log.team is not None and "dist_err" in log.arrays and len(log.tick_t) > 0
    if desired_drawn:
        assert log.team is not None  # desired_drawn says so
        d = np.asarray(log.team["distances"])
        scale = log.values.get("scale", np.ones(len(log.tick_t)))
        desired = scale[:, None] * d[None, :]
        actual = desired + log.arrays["dist_err"][:, : len(d)]
        ids = log.team["ids"]
        edges = log.team["edges"]
        t = log.tick_t - t0
        for k in range(len(d)):
            i, j = edges[k]
            _plot(top, t, actual[:, k], lw=1.2, label=f"{ids[i]}-{ids[j]}")
        for value in np.unique(np.round(desired, 3), axis=1).T:
            _plot(top, t, value, "k--", lw=0.8)
        top.legend(ncol=6, fontsize=7, loc="upper right")
        _shade_phases(top, log, t0)
    elif (pairs := vehicle_distances(log)) is not None:
        t, distances = pairs
        for (a, b), d in distances.items():
            _plot(top, t - t0, d, lw=1.2, label=f"{a}-{b}" if b else f"closest ({a} vehicles)")
        top.legend(ncol=6, fontsize=7, loc="upper right")
        top.set_title("between the vehicles' positions (no desired values: no team header)",
                      fontsize=9)
    else:
        top.text(0.5, 0.5, "distances: fewer than two vehicles with positions in this log",
                 ha="center", va="center", transform=top.transAxes)
    top.set_ylabel("distance [m]")
    for sysid, tr in sorted(log.tracks.items()):
        _plot(bottom, tr.t - t0, tr.v_ned[:, 0], lw=1, label=f"{sysid} vx")
        _plot(bottom, tr.t - t0, tr.v_ned[:, 1], lw=1, ls=":", label=f"{sysid} vy")
    bottom.set_ylabel("velocity [m/s] (x solid, y dotted)")
    bottom.set_xlabel("time [s]")
    bottom.legend(ncol=4, fontsize=7, loc="upper right")
    fig.suptitle("Distances (desired dashed) and velocities" if desired_drawn
                 else "Distances and velocities")
    fig.tight_layout()
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
    fig, ax = plt.subplots(figsize=(7, 7))
    for sysid, tr in sorted(log.tracks.items()):
        if not len(tr.t):
            continue
        _path(ax, tr.p_ned[:, 1], tr.p_ned[:, 0], lw=1, label=f"vehicle {sysid}")
        ax.plot(tr.p_ned[-1, 1], tr.p_ned[-1, 0], "o", ms=4, color=ax.lines[-1].get_color())
    if "payload" in log.arrays:
        p = log.arrays["payload"]
        _path(ax, p[:, 1], p[:, 0], "k-", lw=1.5, label="payload")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("Trajectories (top view)")
    fig.tight_layout()
    return fig


def _distance_errors(log: FlightLog) -> plt.Figure | None:
    if "dist_err" not in log.arrays or log.team is None:
        return None
    t0 = _t0(log)
    fig, ax = plt.subplots(figsize=(10, 4))
    e = log.arrays["dist_err"]
    ids, edges = log.team["ids"], log.team["edges"]
    for k in range(e.shape[1]):
        i, j = edges[k]
        _plot(ax, log.tick_t - t0, e[:, k], lw=1, label=f"{ids[i]}-{ids[j]}")
    _shade_phases(ax, log, t0)
    ax.axhline(0, color="k", lw=0.5)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("distance error e_k [m]")
    ax.legend(ncol=6, fontsize=7)
    ax.set_title("Distance error per edge (formation flight shaded green)")
    fig.tight_layout()
    return fig


def _accelerations(log: FlightLog) -> plt.Figure | None:
    if "acc_cmd" not in log.arrays or not len(log.tick_t):
        return None
    t = log.tick_t - _t0(log)
    acc = log.per_vehicle("acc_cmd", 2)
    ids = log.team["ids"] if log.team is not None else tuple(range(1, log.n_vehicles + 1))
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    for i, vid in enumerate(ids):
        line = _plot(top, t, np.linalg.norm(acc[:, i], axis=1), lw=1, label=f"|a| {vid}")[0]
        _plot(bottom, t, acc[:, i, 0], lw=1, color=line.get_color(), label=f"{vid} x")
        _plot(bottom, t, acc[:, i, 1], lw=1, ls=":", color=line.get_color(), label=f"{vid} y")
    if log.team is not None:
        top.axhline(float(log.team["accel_norm"]), color="r", ls="--", lw=1, label="norm limit")
        for sign in (1.0, -1.0):
            bottom.axhline(sign * float(log.team["accel_axis"]), color="m", ls="--", lw=1,
                           label="per-axis limit" if sign > 0 else None)
    top.set_ylabel("|a| [m/s^2]")
    bottom.set_ylabel("a per axis [m/s^2] (x solid, y dotted)")
    bottom.set_xlabel("time [s]")
    top.legend(ncol=5, fontsize=7)
    bottom.legend(ncol=5, fontsize=7)
    fig.suptitle("Commanded horizontal accelerations against the limits")
    fig.tight_layout()
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
        "missing": log.missing,
        "figures": figures,
    }


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
        lines += ["Not in this log:", ""] + [f"- {x}" for x in s["missing"]]
    lines += ["", "Figures: " + ", ".join(s["figures"])]
    return "\n".join(lines) + "\n"
