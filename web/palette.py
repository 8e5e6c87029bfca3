"""Colours of the scene: what a colour means is decided here, once.

Vehicles are coloured by what they are doing, ropes by how hard they pull and
formation edges by how far they are from their desired length, so an operator
reads the team's health at a glance. Every function returns ``uint8`` RGB.

Two colours belong to one thing each: the green of a vehicle that is ok and
the magenta of the payload. Nothing else in the scene reaches their hues, not
even part-way along a ramp (edges and ropes go from neutral blue-greys to
yellow and red), so the team and its payload stand out from the lines
between them, and a test can find them in a screenshot by colour alone
(``tests/browser/test_live_demo.py``; the rule itself is tested in
``tests/web/test_frame.py``).
"""

from __future__ import annotations

import enum
import functools

import numpy as np

__all__ = [
    "BAD",
    "EDGE_OK",
    "GEOFENCE",
    "GHOST",
    "GROUND_MARK",
    "OK",
    "PAYLOAD",
    "PAYLOAD_ESTIMATED",
    "SLACK",
    "TAUT",
    "TRAIL",
    "UNKNOWN",
    "VELOCITY",
    "WARN",
    "VehicleState",
    "error_colors",
    "ramp",
    "state_colors",
    "tension_colors",
]


class VehicleState(enum.IntEnum):
    """What a vehicle is doing, as the operator needs to see it."""

    OK = 0  # fresh telemetry, flying or ready under GCS control
    STALE = 1  # telemetry older than the safety rule's threshold (or never heard)
    HOLDING = 2  # the autopilot holds position on its own (lost setpoints, hold mode)
    LANDING = 3  # descending to land

    @property
    def text(self) -> str:
        return self.name.lower()


OK = (0, 200, 83)
"""A vehicle that is ok: green, used by nothing else in the scene."""

_STATE_RGB = np.array([
    OK,
    (149, 165, 166),  # STALE: grey
    (243, 156, 18),  # HOLDING: amber
    (155, 89, 182),  # LANDING: purple
], dtype=np.uint8)

PAYLOAD = np.array((214, 0, 150), dtype=np.uint8)  # measured (sim truth): magenta, its own
PAYLOAD_ESTIMATED = np.array((240, 170, 220), dtype=np.uint8)  # from geometry: pale magenta
GHOST = np.array((150, 190, 230), dtype=np.uint8)  # desired shape: faint blue
VELOCITY = np.array((41, 128, 185), dtype=np.uint8)  # velocity arrows: blue
TRAIL = np.array((52, 73, 94), dtype=np.uint8)  # trails: dark slate
UNKNOWN = np.array((120, 120, 120), dtype=np.uint8)  # not measured (NaN)
GEOFENCE = (231, 76, 60)  # the geofence on the ground: red
GROUND_MARK = (69, 90, 100)  # the ground's references (north, origin, the payload's drop
# line and its foot): dark blue-grey, quiet beside the team

EDGE_OK = (96, 125, 139)  # an edge at its desired length: neutral blue-grey
WARN = (241, 196, 15)  # yellow
BAD = (231, 76, 60)  # red
SLACK = (207, 216, 220)  # a slack rope: pale
TAUT = (55, 71, 79)  # a rope at its nominal tension: dark blue-grey, drawn firm
_LUT_SIZE = 257  # odd: the middle stop of a map is an entry


@functools.cache
def _lut(stops: tuple[float, ...], colors: tuple[tuple[int, int, int], ...]) -> np.ndarray:
    """Colours sampled from the piecewise-linear map, from stops[0] to stops[-1]."""
    x = np.linspace(stops[0], stops[-1], _LUT_SIZE)
    table = np.asarray(colors, dtype=float)
    out = np.stack([np.interp(x, stops, table[:, c]) for c in range(3)], axis=-1)
    return np.vstack((np.round(out).astype(np.uint8), UNKNOWN))  # last entry: NaN


def ramp(x: np.ndarray, stops: tuple[float, ...],
         colors: tuple[tuple[int, int, int], ...]) -> np.ndarray:
    """Piecewise-linear colour map: ``x`` (any shape) -> (..., 3) uint8; NaN -> grey.

    Values are clipped to the first and last stop; a 257-entry table keeps it cheap
    enough to run for every rope and edge at the frame rate.
    """
    lo, hi = stops[0], stops[-1]
    index = (np.asarray(x, dtype=float) - lo) * ((_LUT_SIZE - 1) / (hi - lo)) + 0.5
    np.clip(index, 0.0, _LUT_SIZE - 0.5, out=index)  # NaN stays NaN
    index[np.isnan(index)] = _LUT_SIZE  # the table's last entry
    return _lut(stops, colors)[index.astype(np.intp)]


def state_colors(states: np.ndarray) -> np.ndarray:
    """(n,) VehicleState values -> (n, 3)."""
    return _STATE_RGB[np.asarray(states, dtype=int)]


def tension_colors(tension: np.ndarray, nominal: float) -> np.ndarray:
    """Rope tension, N -> colour: slack pale, nominal dark blue-grey, twice nominal red."""
    return ramp(np.asarray(tension) / nominal, (0.0, 1.0, 2.0), (SLACK, TAUT, BAD))


def error_colors(error: np.ndarray, full: float) -> np.ndarray:
    """Distance error, m -> colour: neutral blue-grey at 0 (nothing to see), yellow at
    ``full / 2``, red from ``full``."""
    return ramp(np.abs(np.asarray(error)) / full, (0.0, 0.5, 1.0), (EDGE_OK, WARN, BAD))
