"""The lift: the altitude where the payload leaves the ground (at the smallest scale, the
steepest ropes) plus the lift height, against the ceiling it must stay under
(``operator.altitude_max`` and the geofence).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from gcs.analysis._team_load import hang_depth
from gcs.config import Team

__all__ = ["Lift", "lift"]


class Lift(NamedTuple):
    """Where the lift starts and ends, and the ceiling (altitudes, m)."""

    depth: float | None
    """The vehicles' altitude when the payload leaves the ground (None: the ropes cannot
    hang it)."""
    top: float
    """The altitude the lift climbs to (inf when the ropes cannot hang the payload)."""
    ceiling: float


def lift(team: Team) -> Lift:
    """The lift of ``team``'s payload at ``guidance.scale_min``."""
    cfg = team.config
    ceiling = min(cfg.operator.altitude_max, cfg.safety.geofence_altitude)
    try:
        depth = hang_depth(team, scale=cfg.guidance.scale_min)
    except ValueError:
        return Lift(None, math.inf, ceiling)
    return Lift(depth, depth + cfg.flight.lift_height, ceiling)
