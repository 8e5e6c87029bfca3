"""Live plots like the paper's experiment figure, drawn with viser's uPlot.

Top: every controlled inter-vehicle distance with the desired values as
black dashed lines (they follow the operator's scale). Below: the vehicles'
x (north) and y (east) velocities. uPlot is viser's fast time-series chart;
a whole window is one message per chart per tick.

The time axis is "seconds before now" and always spans exactly the window
(the oldest value is held back to its left edge while the window fills):
viser's client keeps a chart's x zoom relative to the data's extent, and an
extent that never changes keeps the whole window in view, even in a browser
too busy to redraw between two updates.
"""

from __future__ import annotations

import numpy as np
import viser
import viser.uplot as uplot

from web._frame import TeamView
from web._history import History

__all__ = ["MAX_SERIES", "PlotsView"]

MAX_SERIES = 12
"""At most this many edges and vehicles are plotted (a larger team plots its first ones)."""

_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
           "#7f7f7f", "#bcbd22", "#17becf", "#393b79", "#637939")


def _line(label: str, k: int) -> uplot.Series:
    return uplot.Series(label=label, stroke=_COLORS[k % len(_COLORS)], width=1.5)


class PlotsView:
    """Three charts fed from a :class:`History`.

    Args:
        gui: where to add the charts (e.g. inside a tab).
        view: the team.
        labels: edge labels, e.g. ``("1-2", ...)``.
        window: span shown, s (the history should keep at least this much).
    """

    def __init__(self, gui: viser.GuiApi, view: TeamView, labels: tuple[str, ...], *,
                 window: float = 60.0) -> None:
        self._edges = np.arange(min(len(labels), MAX_SERIES))
        self._vehicles = np.arange(min(view.n, MAX_SERIES))
        # one dashed line per distinct desired distance, from its first edge
        base = np.round(view.distances[self._edges], 3)
        _, first = np.unique(base, return_index=True)
        self._desired = self._edges[np.sort(first)]
        x = uplot.Series(label="s ago")
        dist_series = (x,
                       *(_line(labels[k], int(k)) for k in self._edges),
                       *(uplot.Series(label=f"desired {view.distances[k]:.2f}", stroke="#000",
                                      dash=(6.0, 4.0), width=1.2) for k in self._desired))
        self.window = window
        x0 = np.array([-window, 0.0])
        start = (x0, *(np.full(2, view.distances[k]) for k in self._edges),
                 *(np.full(2, view.distances[k]) for k in self._desired))
        axes = (uplot.Axis(label="seconds before now"), uplot.Axis(label="m"))
        self.distances = gui.add_uplot(start, dist_series,
                                       title="distances (m)", aspect=1.6,
                                       scales={"x": uplot.Scale(time=False)}, axes=axes)
        vel_series = (x, *(_line(f"{view.ids[i]}", int(i)) for i in self._vehicles))
        vaxes = (uplot.Axis(label="seconds before now"), uplot.Axis(label="m/s"))
        still = (x0, *(np.zeros(2) for _ in self._vehicles))
        self.vx = gui.add_uplot(still, vel_series,
                                title="velocity x, north (m/s)", aspect=2.0,
                                scales={"x": uplot.Scale(time=False)}, axes=vaxes)
        self.vy = gui.add_uplot(still, vel_series,
                                title="velocity y, east (m/s)", aspect=2.0,
                                scales={"x": uplot.Scale(time=False)}, axes=vaxes)

    def update(self, history: History) -> None:
        """Show the history's window."""
        s = history.series()
        if len(s.t) == 0:
            return
        ago = s.t - s.t[-1]
        keep = ago > -self.window
        x = np.concatenate(([-self.window], ago[keep]))

        def held(values: np.ndarray) -> tuple[np.ndarray, ...]:
            """Columns of ``values`` (k, c) with the oldest kept row repeated at the left edge."""
            v = values[keep]
            return tuple(np.concatenate((v[:1], v)).T)

        self.distances.data = (x, *held(s.distance[:, self._edges]),
                               *held(s.desired[:, self._desired]))
        self.vx.data = (x, *held(s.vx[:, self._vehicles]))
        self.vy.data = (x, *held(s.vy[:, self._vehicles]))
