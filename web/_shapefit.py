"""Where the desired shape would be if the team were perfect: the ghost.

The guidance controls distances only, so the desired shape has no place or
heading of its own. To compare, the desired positions (scaled) are rotated and
translated onto the current team by least squares (2-D Procrustes without
scaling or reflection); what is left over is the team's deformation.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["fit_shape"]


def fit_shape(desired_xy: np.ndarray, actual_xy: np.ndarray) -> np.ndarray | None:
    """Desired positions (n, 2) moved rigidly onto ``actual_xy`` (n, 2); None if unknown.

    Vehicles with a NaN position are left out of the fit; fewer than two known
    vehicles leave the rotation undetermined and give None.
    """
    known = np.isfinite(actual_xy).all(axis=1)
    count = int(known.sum())
    if count < 2:
        return None
    d, a = (desired_xy, actual_xy) if count == len(known) else (desired_xy[known],
                                                               actual_xy[known])
    d_mean, a_mean = d.sum(axis=0) / count, a.sum(axis=0) / count
    dc, ac = d - d_mean, a - a_mean
    # optimal angle of the 2-D rotation taking dc onto ac
    cross = float(dc[:, 0] @ ac[:, 1] - dc[:, 1] @ ac[:, 0])
    dot = float(np.vdot(dc, ac))
    theta = math.atan2(cross, dot)
    c, s = math.cos(theta), math.sin(theta)
    return (desired_xy - d_mean) @ np.array([[c, s], [-s, c]]) + a_mean
