"""How every report figure looks: a colour per vehicle, the phase key, legends off the data,
limits marked without squashing the data, and the files (SVG and 200 dpi PNG).

One place for these so the four figures agree: vehicle 3 is the same colour in
the top view, the velocities and the accelerations, and a phase has one shade
and one key everywhere.
"""

from __future__ import annotations

import io
import math
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.artist import Artist
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from PIL import Image

from gcs.flightlog._shades import PHASE_SHADES

__all__ = ["DPI", "FORMATS", "LIMIT_IN_VIEW", "PHASE_SHADES", "PNG_COLOURS", "axis_styles",
           "edge_colours", "legend_outside", "mark_limit", "phase_key", "save_figure",
           "shade_phases", "vehicle_colours"]

DPI = 200
"""Resolution of the PNGs: sharp when printed or zoomed; the SVGs scale without limit."""

PNG_COLOURS = 64
"""Colours of a PNG's palette: a figure of lines on a few shades needs no more (the
antialiased edges lose a little), and a 200 dpi figure shrinks about four times,
to 40-130 kB, small enough to mail or put in a document. The SVG keeps every colour."""

FORMATS = ("svg", "png")
"""Every figure is written in each: vector for documents, raster for anything else."""

LIMIT_IN_VIEW = 2.0
"""A limit up to this many times the data's peak is drawn as a line inside the axes; a
higher one would squash the data to a sliver, so the axes keep to the data and an arrow
at their edge says where the limit is."""

_HEADROOM = 1.35
"""Axes kept to the data end this far past its peak (from zero; twice that span about
zero for a signed quantity, which gets an arrow at each edge), so the arrow marking a
limit off the scale sits in a band no data reaches."""

_TAB10 = plt.get_cmap("tab10")


def vehicle_colours(ids: Iterable[int]) -> dict[int, tuple[float, float, float, float]]:
    """One colour per vehicle, by ascending id: tab10 up to ten, a spread of turbo beyond."""
    order = sorted(set(ids))
    if len(order) <= 10:
        return {vid: _TAB10(k) for k, vid in enumerate(order)}
    turbo = plt.get_cmap("turbo")
    return {vid: turbo(0.05 + 0.9 * k / (len(order) - 1)) for k, vid in enumerate(order)}


def edge_colours(n: int) -> list[tuple[float, float, float, float]]:
    """Colours of ``n`` edges (pairs of vehicles), from a ramp unlike the vehicles' palette."""
    viridis = plt.get_cmap("viridis")
    return [viridis(0.9 * k / max(n - 1, 1)) for k in range(n)]


def axis_styles() -> list[Artist]:
    """Legend entries saying which line style is x and which is y."""
    return [Line2D([], [], color="0.3", lw=1, label="x (solid)"),
            Line2D([], [], color="0.3", lw=1, ls=":", label="y (dotted)")]


def legend_outside(ax: plt.Axes, handles: Sequence[Artist], **kwargs: Any) -> None:
    """The legend right of the axes, never on the data; long ones in columns."""
    if not handles:
        return
    ax.legend(handles=list(handles), loc="upper left", bbox_to_anchor=(1.01, 1.0),
              borderaxespad=0.0, fontsize=7, title_fontsize=7,
              ncol=math.ceil(len(handles) / 14), **kwargs)


def shade_phases(ax: plt.Axes, changes: Sequence[tuple[float, str]], end: float,
                 t0: float) -> list[str]:
    """Shade the payload phases of ``changes`` (absolute times) on ``ax``; the phases shaded."""
    shaded: list[str] = []
    for k, (t, name) in enumerate(changes):
        stop = changes[k + 1][0] if k + 1 < len(changes) else end
        if name in PHASE_SHADES:
            ax.axvspan(t - t0, stop - t0, color=PHASE_SHADES[name], zorder=0, lw=0)
            if name not in shaded:
                shaded.append(name)
    return shaded


def phase_key(fig: plt.Figure, shaded: Iterable[str]) -> None:
    """The key of the phase shading, one entry per phase shaded, below the axes."""
    names = [name for name in PHASE_SHADES if name in set(shaded)]
    if not names:
        return
    handles = [Patch(facecolor=PHASE_SHADES[name], edgecolor="0.6", lw=0.5, label=name)
               for name in names]
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=7,
               title="phase (shaded)", title_fontsize=7, frameon=False)


def mark_limit(ax: plt.Axes, limit: float, peak: float, *, label: str, unit: str,
               colour: str, symmetric: bool = False) -> Line2D | None:
    """Mark ``limit`` on axes showing data up to ``peak``; the line drawn, or None.

    Within :data:`LIMIT_IN_VIEW` times the peak the limit is a dashed line (at
    ±limit when ``symmetric``) and the axes hold both. Beyond, the axes keep to the
    data with some headroom and an arrow at their top (and bottom) edge points to
    the limit off the scale, with its value.
    """
    top = peak if math.isfinite(peak) and peak > 0 else 0.0
    if top == 0.0 or limit <= LIMIT_IN_VIEW * top:
        line: Line2D = ax.axhline(limit, color=colour, ls="--", lw=1, label=label)
        if symmetric:
            ax.axhline(-limit, color=colour, ls="--", lw=1)
        return line
    span = _HEADROOM * top * (1.2 if symmetric else 1.0)
    ax.set_ylim(-span if symmetric else 0.0, span)
    for sign in (1.0, -1.0) if symmetric else (1.0,):
        edge = 1.0 if sign > 0 else 0.0
        value = f"{'+' if sign > 0 else '-'}{limit:.2f}" if symmetric else f"{limit:.2f}"
        ax.annotate(f"{label} {value} {unit} off the scale ({limit / top:.1f}x the peak)",
                    xy=(0.99, edge), xycoords="axes fraction",
                    xytext=(0.99, edge - sign * 0.12), textcoords="axes fraction",
                    ha="right", va="center", fontsize=7, color=colour,
                    arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 1.2,
                                "relpos": (1.0, 1.0 if sign > 0 else 0.0), "shrinkA": 1,
                                "shrinkB": 0, "mutation_scale": 12})
    return None


def save_figure(fig: plt.Figure, out: Path, stem: str) -> list[str]:
    """Write ``fig`` as ``stem.svg`` and ``stem.png`` (:data:`DPI`, :data:`PNG_COLOURS`)
    into ``out``; the names written.

    No date in the files and fixed SVG ids: the same log gives the same bytes.
    """
    with plt.rc_context({"svg.hashsalt": "gcs-report"}):
        fig.savefig(out / f"{stem}.svg", metadata={"Date": None})
    raw = io.BytesIO()
    fig.savefig(raw, format="png", dpi=DPI)
    with Image.open(raw) as image:
        small = image.convert("RGB").quantize(colors=PNG_COLOURS, dither=Image.Dither.NONE,
                                              method=Image.Quantize.FASTOCTREE)
    small.save(out / f"{stem}.png", dpi=(DPI, DPI), optimize=True)
    return [f"{stem}.{ext}" for ext in FORMATS]
