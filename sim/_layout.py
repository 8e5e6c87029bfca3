"""Start layouts of a team around its payload: positions, rope lengths, payload position.

The paper's square (side 1 m, ropes sqrt(1.25) m, payload at the centre) is a
ring of four vehicles at radius sqrt(0.5) m turned by 45 degrees; larger
teams use bigger rings so that neighbours keep their spacing. Everything
starts on the ground (NED z = 0).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["Layout", "paper_square", "ring_layout"]


class Layout(NamedTuple):
    """Arrays :class:`sim.World` takes to place a team."""

    p0_ned: np.ndarray
    """(N, 3) vehicle start positions, m."""
    rope_length: np.ndarray
    """(N,) rope lengths, m."""
    payload_p0_ned: np.ndarray
    """(3,) payload start position, m."""


def ring_layout(n_vehicles: int, *, spacing: float = 0.8, hang_depth: float = math.sqrt(0.75),
                phase: float = 0.0, ground_z_ned: float = 0.0) -> Layout:
    """``n_vehicles`` evenly on a circle with ``spacing`` m between neighbours, payload at
    the centre, ropes long enough to hang it ``hang_depth`` m below the ring.

    Vehicle ``k`` sits at angle ``phase + 2 pi k / N`` from north (rad); a
    single vehicle sits ``spacing`` m from the payload.
    """
    if n_vehicles < 1 or not spacing > 0.0 or not hang_depth > 0.0:
        raise ValueError(f"need n_vehicles >= 1, spacing > 0 and hang_depth > 0, got "
                         f"{n_vehicles}, {spacing}, {hang_depth}")
    radius = spacing if n_vehicles == 1 else spacing / (2.0 * math.sin(math.pi / n_vehicles))
    angle = phase + 2.0 * math.pi * np.arange(n_vehicles) / n_vehicles
    p0 = np.column_stack([radius * np.cos(angle), radius * np.sin(angle),
                          np.full(n_vehicles, ground_z_ned)])
    rope = np.full(n_vehicles, math.hypot(radius, hang_depth))
    return Layout(p0, rope, np.array([0.0, 0.0, ground_z_ned]))


def paper_square() -> Layout:
    """The paper's team: four vehicles on a 1 m square, ropes sqrt(1.25) m, payload centred.

    Vehicles 0..3 sit at north-east, north-west, south-west, south-east corners.
    """
    return ring_layout(4, spacing=1.0, hang_depth=math.sqrt(0.75), phase=math.pi / 4.0)
