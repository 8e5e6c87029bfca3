"""Colours of the scene: what a colour means is decided here, once.

Vehicles are coloured by what they are doing, ropes by how hard they pull and
formation edges by how far they are from their desired length, so an operator
reads the team's health at a glance. Every function returns ``uint8`` RGB.
"""

from __future__ import annotations

import enum
import functools

import numpy as np

__all__ = [
    "GHOST",
    "PAYLOAD",
    "PAYLOAD_ESTIMATED",
    "TRAIL",
    "UNKNOWN",
    "VELOCITY",
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


_STATE_RGB = np.array([
    (46, 204, 113),  # OK: green
    (149, 165, 166),  # STALE: grey
    (243, 156, 18),  # HOLDING: amber
    (155, 89, 182),  # LANDING: purple
], dtype=np.uint8)

PAYLOAD = np.array((230, 126, 34), dtype=np.uint8)  # measured (sim truth): orange
PAYLOAD_ESTIMATED = np.array((240, 190, 140), dtype=np.uint8)  # from geometry: pale
GHOST = np.array((150, 190, 230), dtype=np.uint8)  # desired shape: faint blue
VELOCITY = np.array((41, 128, 185), dtype=np.uint8)  # velocity arrows: blue
TRAIL = np.array((52, 73, 94), dtype=np.uint8)  # trails: dark slate
UNKNOWN = np.array((120, 120, 120), dtype=np.uint8)  # not measured (NaN)

_GOOD = (46, 204, 113)
_WARN = (241, 196, 15)
_BAD = (231, 76, 60)
_SLACK = (120, 144, 156)
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
    """Rope tension, N -> colour: slack grey-blue, nominal green, twice nominal red."""
    return ramp(np.asarray(tension) / nominal, (0.0, 1.0, 2.0), (_SLACK, _GOOD, _BAD))


def error_colors(error: np.ndarray, full: float) -> np.ndarray:
    """Distance error, m -> colour: green at 0, yellow at ``full / 2``, red from ``full``."""
    return ramp(np.abs(np.asarray(error)) / full, (0.0, 0.5, 1.0), (_GOOD, _WARN, _BAD))
