"""Where a team starts: its desired shape on the ground around the NED origin.

Why: the sim must start the team the way the GCS expects to find it, so the
start comes from the same team file the GCS flies: each vehicle at its
desired position (team body frame x forward, y right, which is north and east
at heading 0), the payload on the ground at the centroid (the origin), every
rope as long as the payload configuration says.
"""

from __future__ import annotations

import numpy as np

from gcs.config import Team
from sim._layout import Layout

__all__ = ["team_layout"]


def team_layout(team: Team, *, ground_z_ned: float = 0.0) -> Layout:
    """Start positions (team order), rope lengths and payload position of ``team``."""
    xy = np.asarray(team.formation.positions, dtype=np.float64)
    n = xy.shape[0]
    p0 = np.column_stack([xy, np.full(n, ground_z_ned)])
    rope = np.array(team.config.payload.lengths(n), dtype=np.float64)
    return Layout(p0, rope, np.array([0.0, 0.0, ground_z_ned]))
