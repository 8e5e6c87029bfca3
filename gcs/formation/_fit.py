"""Where the desired shape would be if the team were perfect: the ghost.

The guidance controls distances only, so the desired shape has no place or
heading of its own. To compare, the desired positions (scaled) are rotated and
translated onto the current team by least squares (2-D Procrustes without
scaling or reflection); what is left over is the team's deformation.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["fit_rotation", "fit_shape"]


def fit_rotation(desired_xy: np.ndarray, actual_xy: np.ndarray) -> float | None:
    """Angle (rad, from north towards east) of the rotation taking the desired shape onto
    ``actual_xy``: the team's heading; None if fewer than two vehicles are known.

    The operator's sticks move the team along this heading's axes (the guidance's
    body frame), so the geofence needs it to tell which stick points outward.
    """
    fit = _fit(desired_xy, actual_xy)
    return None if fit is None else fit[0]


def fit_shape(desired_xy: np.ndarray, actual_xy: np.ndarray) -> np.ndarray | None:
    """Desired positions (n, 2) moved rigidly onto ``actual_xy`` (n, 2); None if unknown.

    Vehicles with a NaN position are left out of the fit; fewer than two known
    vehicles leave the rotation undetermined and give None.
    """
    fit = _fit(desired_xy, actual_xy)
    if fit is None:
        return None
    theta, d_mean, a_mean = fit
    c, s = math.cos(theta), math.sin(theta)
    return (desired_xy - d_mean) @ np.array([[c, s], [-s, c]]) + a_mean


def _fit(desired_xy: np.ndarray, actual_xy: np.ndarray
         ) -> tuple[float, np.ndarray, np.ndarray] | None:
    """Least-squares rotation angle and the two centroids (known vehicles only)."""
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
    return math.atan2(cross, dot), d_mean, a_mean
