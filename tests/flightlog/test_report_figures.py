"""The report's figures as an operator reads them, drawn from a real recorded flight.

Each figure is an SVG and a 200 dpi PNG; a vehicle keeps one colour in every
figure (its x and y lines told apart by style, with a key); the phase shading
has a key; no legend sits on the data; the accelerations are scaled to the
data, with a limit far above them marked at the edge rather than squashing them.
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.colors import to_hex
from matplotlib.figure import Figure
from matplotlib.legend import Legend
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Polygon, Rectangle
from matplotlib.text import Annotation
from PIL import Image

from gcs.flightlog import FlightLog, write_report
from gcs.flightlog import _report as report
from gcs.flightlog._report import FIGURES

SVG = "{http://www.w3.org/2000/svg}svg"


@pytest.fixture(scope="module")
def log(short_flight: tuple[dict, Path]) -> FlightLog:
    return FlightLog.load(short_flight[1])


@pytest.fixture(scope="module")
def figures(log: FlightLog) -> Iterator[dict[str, Figure]]:
    """The four figures of the short flight, drawn (so legends and axes have their places)."""
    drawn: dict[str, Figure] = {}
    for stem, draw in (("formation", report._formation), ("trajectories", report._trajectories),
                       ("distance_errors", report._distance_errors),
                       ("accelerations", report._accelerations)):
        fig = draw(log)
        assert fig is not None, stem
        fig.canvas.draw()
        drawn[stem] = fig
    assert tuple(drawn) == FIGURES
    yield drawn
    for fig in drawn.values():
        plt.close(fig)


def test_each_figure_is_an_svg_and_a_small_200_dpi_png(log: FlightLog, tmp_path: Path) -> None:
    summary = write_report(log, tmp_path)
    assert summary["figures"] == [f"{stem}.{ext}" for stem in FIGURES for ext in ("svg", "png")]
    for stem in FIGURES:
        root = ET.parse(tmp_path / f"{stem}.svg").getroot()
        assert root.tag == SVG, stem
        assert len(root.findall(".//{http://www.w3.org/2000/svg}path")) > 20, stem
        with Image.open(tmp_path / f"{stem}.png") as png:
            assert [round(d) for d in png.info["dpi"]] == [200, 200], stem
            assert png.width >= 1600, stem  # 8 to 10 inches wide at 200 dpi
        assert (tmp_path / f"{stem}.png").stat().st_size < 150_000, stem  # mailable


def _vehicle_lines(fig: Figure) -> dict[int, list[plt.Line2D]]:
    """The data lines of each vehicle, by their labels (``vehicle 3 x``, ``vehicle 3``)."""
    out: dict[int, list[plt.Line2D]] = defaultdict(list)
    for ax in fig.axes:
        for line in ax.get_lines():
            words = str(line.get_label()).split()
            if len(words) >= 2 and words[0] == "vehicle":
                out[int(words[1])].append(line)
    return out


def test_a_vehicle_has_one_colour_in_every_figure(figures: dict[str, Figure]) -> None:
    seen: dict[int, str] = {}
    for name in ("formation", "trajectories", "accelerations"):
        by_vehicle = _vehicle_lines(figures[name])
        assert sorted(by_vehicle) == [1, 2, 3, 4], name
        colours = {}
        for vid, lines in by_vehicle.items():
            assert len({to_hex(line.get_color()) for line in lines}) == 1, (name, vid)
            colours[vid] = to_hex(lines[0].get_color())
            assert seen.setdefault(vid, colours[vid]) == colours[vid], (name, vid)
        assert len(set(colours.values())) == 4, name  # and no two vehicles share one


def test_x_and_y_differ_by_style_and_the_legend_says_which(figures: dict[str, Figure]) -> None:
    for name, ax in (("formation", figures["formation"].axes[1]),
                     ("accelerations", figures["accelerations"].axes[1])):
        styles: dict[str, set[str]] = {}
        for line in ax.get_lines():
            words = str(line.get_label()).split()
            if words[0] == "vehicle":
                styles.setdefault(words[2], set()).add(str(line.get_linestyle()))
        assert styles == {"x": {"-"}, "y": {":"}}, name
        legend = ax.get_legend()
        assert legend is not None, name
        keyed = {t.get_text(): h.get_linestyle() for t, h in zip(
            legend.get_texts(), legend.legend_handles, strict=True) if isinstance(h, Line2D)}
        assert keyed["x (solid)"] == "-" and keyed["y (dotted)"] == ":", name


def _shades(ax: plt.Axes) -> set[str]:
    return {to_hex(p.get_facecolor()) for p in ax.patches if isinstance(p, (Polygon, Rectangle))}


def test_the_phase_shading_has_a_key_entry_per_phase(figures: dict[str, Figure]) -> None:
    for name in ("formation", "distance_errors", "accelerations"):
        fig = figures[name]
        keys = [legend for legend in fig.legends if legend.get_title().get_text().startswith(
            "phase")]
        assert len(keys) == 1, name
        key = keys[0]
        assert [t.get_text() for t in key.get_texts()] == ["lifting", "formation",
                                                           "setting down"], name
        keyed = {to_hex(h.get_facecolor()) for h in key.legend_handles if isinstance(h, Patch)}
        assert len(keyed) == 3, name
        for ax in fig.axes:
            if _shades(ax):
                assert _shades(ax) == keyed, name


def test_no_legend_sits_on_the_data(figures: dict[str, Figure]) -> None:
    for name, fig in figures.items():
        legends: list[Legend] = [*fig.legends]
        legends += [legend for ax in fig.axes if (legend := ax.get_legend()) is not None]
        assert legends, name
        for legend in legends:
            box = legend.get_window_extent()
            for ax in fig.axes:
                plot = ax.get_window_extent()
                overlap_x = min(box.x1, plot.x1) - max(box.x0, plot.x0)
                overlap_y = min(box.y1, plot.y1) - max(box.y0, plot.y0)
                assert overlap_x <= 1 or overlap_y <= 1, (name, legend.get_texts()[0])


def _levels(ax: plt.Axes) -> set[float]:
    """Horizontal lines other than zero: y constant along the line."""
    return {round(float(y[0]), 6) for line in ax.get_lines()
            if len(y := np.asarray(line.get_ydata(), dtype=float)) == 2 and y[0] == y[1] != 0}


def test_accelerations_keep_to_the_data_and_mark_a_far_limit_at_the_edge(
        figures: dict[str, Figure], log: FlightLog) -> None:
    assert log.team is not None
    norm_ax, axis_ax = figures["accelerations"].axes
    acc = log.per_vehicle("acc_cmd", 2)
    peak_norm = float(np.nanmax(np.linalg.norm(acc, axis=2)))
    peak_axis = float(np.nanmax(np.abs(acc)))
    norm, per_axis = float(log.team["accel_norm"]), float(log.team["accel_axis"])
    assert norm > 4 * peak_norm and per_axis > 4 * peak_axis  # this flight: far below
    low, high = norm_ax.get_ylim()
    assert low == 0 and peak_norm < high < 1.5 * peak_norm  # the data fill the axes
    low, high = axis_ax.get_ylim()
    assert -2 * peak_axis < low < -peak_axis and peak_axis < high < 2 * peak_axis
    assert _levels(norm_ax) == set() and _levels(axis_ax) == set()  # no line off the scale
    for ax, marks in ((norm_ax, {f"norm limit {norm:.2f}": 1.0}),
                      (axis_ax, {f"per-axis limit +{per_axis:.2f}": 1.0,
                                 f"per-axis limit -{per_axis:.2f}": 0.0})):
        notes = [c for c in ax.get_children() if isinstance(c, Annotation)]
        for text, edge in marks.items():
            note = next(n for n in notes if n.get_text().startswith(text))
            assert "off the scale" in note.get_text()
            assert note.xy == pytest.approx((0.99, edge))  # the arrow's head at the edge
            assert note.arrow_patch is not None


def test_a_limit_near_the_data_is_a_line_within_the_axes(log: FlightLog) -> None:
    assert log.team is not None
    acc = log.per_vehicle("acc_cmd", 2)
    norm = round(1.5 * float(np.nanmax(np.linalg.norm(acc, axis=2))), 6)
    per_axis = round(1.5 * float(np.nanmax(np.abs(acc))), 6)
    fig = report._accelerations(dataclasses.replace(
        log, team={**log.team, "accel_norm": norm, "accel_axis": per_axis}))
    assert fig is not None
    norm_ax, axis_ax = fig.axes
    assert _levels(norm_ax) == {norm}
    assert _levels(axis_ax) == {per_axis, -per_axis}
    assert norm_ax.get_ylim()[1] > norm and axis_ax.get_ylim()[0] < -per_axis
    assert not [c for ax in fig.axes for c in ax.get_children() if isinstance(c, Annotation)]
    plt.close(fig)
