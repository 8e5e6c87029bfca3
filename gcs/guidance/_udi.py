"""The guidance's per-vehicle arithmetic, compiled: eq. udi and its local frames as loops.

Why: the law is a few dozen multiply-adds per edge, but written as numpy
array expressions it takes about forty calls, each paying numpy's cost per
call; for a hundred vehicles that is a large share of the 4 Hz loop's
one-millisecond budget, and the same arithmetic in numba loops a small one
(figures: docs/performance.md, bench/gcs_tick.py). The maths is
documented in :mod:`gcs.guidance._law`, which wraps these kernels; they take and
return plain numpy arrays (float64, C order) and never see anything but what
each vehicle senses in its own frame.
"""

from __future__ import annotations

import math

import numpy as np

from gcs.common import kernel

__all__ = ["finite_max_norm", "local_frames", "to_ned_saturated", "udi"]

_EPS = 1e-9


@kernel()
def local_frames(p: np.ndarray, v: np.ndarray, yaw: np.ndarray, neighbour: np.ndarray,
                 mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Own velocity and neighbours' relative positions/velocities in each vehicle's frame.

    ``p``, ``v``: (n, 2) NED; ``yaw``: (n,); ``neighbour``/``mask``: (n, S) slots.
    Returns ``v_own`` (n, 2), ``rel_p`` = p_j - p_i and ``rel_v`` = v_j - v_i
    (n, S, 2), zero in unused slots.
    """
    n, slots = neighbour.shape
    v_own = np.empty((n, 2))
    rel_p = np.zeros((n, slots, 2))
    rel_v = np.zeros((n, slots, 2))
    for i in range(n):
        c, s = math.cos(yaw[i]), -math.sin(yaw[i])  # rotation by -yaw
        v_own[i, 0] = c * v[i, 0] - s * v[i, 1]
        v_own[i, 1] = s * v[i, 0] + c * v[i, 1]
        for k in range(slots):
            if mask[i, k]:
                j = neighbour[i, k]
                dx, dy = p[j, 0] - p[i, 0], p[j, 1] - p[i, 1]
                rel_p[i, k, 0] = c * dx - s * dy
                rel_p[i, k, 1] = s * dx + c * dy
                dx, dy = v[j, 0] - v[i, 0], v[j, 1] - v[i, 1]
                rel_v[i, k, 0] = c * dx - s * dy
                rel_v[i, k, 1] = s * dx + c * dy
    return v_own, rel_p, rel_v


@kernel()
def udi(v_own: np.ndarray, rel_p: np.ndarray, rel_v: np.ndarray, mask: np.ndarray,
        d: np.ndarray, alpha_v: np.ndarray, alpha_a: np.ndarray, c1: float, c2: float,
        lead: float, omega: float, turn_compensation: bool) -> np.ndarray:
    """Eq. udi per vehicle in its own frame, with the hold compensation ``lead`` (s) and,
    with ``turn_compensation``, the feed-forward of the turn its edges make in place of
    the commanded rate ``omega`` (rad/s about down).

    Shapes and meaning as :func:`gcs.guidance._law.formation_acceleration`. A slot
    whose edge has no length (or an unknown one) contributes nothing.
    """
    n, slots = mask.shape
    u = np.empty((n, 2))
    for i in range(n):
        ux, uy = -c1 * v_own[i, 0], -c1 * v_own[i, 1]
        fx, fy = 0.0, 0.0  # c1 times the vehicle's desired velocity, A_v zhat
        turn, edges = 0.0, 0  # the turn rate of its edges, rad/s
        for k in range(slots):
            qx, qy = -rel_p[i, k, 0], -rel_p[i, k, 1]  # p_i - p_j
            dist = math.sqrt(qx * qx + qy * qy)
            if not (mask[i, k] and dist > _EPS):
                continue
            rx, ry = -rel_v[i, k, 0], -rel_v[i, k, 1]  # its rate
            turn += (qx * ry - qy * rx) / (dist * dist)
            edges += 1
            e = dist - d[i, k] + lead * (qx * rx + qy * ry) / dist  # error, predicted
            fx += alpha_v[i, k] * qx / dist
            fy += alpha_v[i, k] * qy / dist
            ax, ay = qx + lead * rx, qy + lead * ry  # the edge half a period ahead
            ahead = math.sqrt(ax * ax + ay * ay)
            if ahead > _EPS:
                gain = (alpha_a[i, k] - c2 * e) / ahead
                ux += gain * ax
                uy += gain * ay
        ux, uy = ux + fx, uy + fy
        if turn_compensation and c1 > 0.0 and edges > 0:
            # w z x v_own - omega z x v_desired, w its edges' mean turn rate
            w = turn / edges
            ux += -w * v_own[i, 1] + omega * fy / c1
            uy += w * v_own[i, 0] - omega * fx / c1
        u[i, 0], u[i, 1] = ux, uy
    return u


@kernel()
def to_ned_saturated(u: np.ndarray, yaw: np.ndarray, norm_max: float,
                     axis_max: float) -> np.ndarray:
    """Each vehicle's (n, 2) acceleration rotated by its yaw into NED, limited in norm
    (direction kept), then per axis."""
    n = u.shape[0]
    out = np.empty((n, 2))
    for i in range(n):
        c, s = math.cos(yaw[i]), math.sin(yaw[i])
        x = c * u[i, 0] - s * u[i, 1]
        y = s * u[i, 0] + c * u[i, 1]
        norm = math.sqrt(x * x + y * y)
        if norm > norm_max:
            x, y = x * norm_max / norm, y * norm_max / norm
        out[i, 0] = min(max(x, -axis_max), axis_max)
        out[i, 1] = min(max(y, -axis_max), axis_max)
    return out


@kernel()
def finite_max_norm(accel: np.ndarray) -> float:
    """Zero the non-finite entries of ``accel`` (n, 2) in place; the largest row norm left.

    Why one kernel: the loop must never send a NaN, and the safety bound wants
    the largest command; as numpy calls that is four calls per tick.
    """
    largest = 0.0
    for i in range(accel.shape[0]):
        for k in range(2):
            if not math.isfinite(accel[i, k]):
                accel[i, k] = 0.0
        largest = max(largest, math.sqrt(accel[i, 0] * accel[i, 0] + accel[i, 1] * accel[i, 1]))
    return largest
