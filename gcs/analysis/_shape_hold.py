"""How firmly the guidance holds the team's shape: its weakest deformation mode.

Near the desired shape, eq. udi pulls each edge back along itself with ``c2`` times
its distance error: a network of springs of stiffness ``c2 R^T R``, ``R`` the rigidity
matrix with unit edge directions (scale-free: it depends on the shape's angles only).
Its smallest non-zero eigenvalue is the stiffness of the shape's weakest mode: 2.0 for
the square with its diagonals, 0.88 for the hexagon, 0.0099 for a ring of twelve tied
to its first and second neighbours. A soft mode is held loosely: a small acceleration
the guidance neither commands nor sees (an autopilot's tracking residual, gusts, the
ropes' pull while the team moves) bends the shape far.

Under a steady disturbance ``d`` of at most ``a`` per vehicle, the edges' errors ``e``
settle where ``c2 R^T e = d``; with ``e`` in the range of ``R``,
``||e|| <= ||d|| / (c2 sigma_min) <= sqrt(n) a / (c2 sigma_min)``, ``sigma_min`` the
square root of that eigenvalue. The largest single edge error is at most ``||e||``.
The ring of twelve, which the rest of the analysis passes, comes apart in the
simulator through the paper flight (1.01 m of distance error against a safe
deformation of 0.83 m); with ``a = 0.016 m/s^2`` this bound already reaches that.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs.formation import Formation, rigidity_matrix

__all__ = ["ShapeHold", "drift_error", "shape_hold", "stiffening_edges", "weakest_mode"]


_SEARCHED_PAIRS = 600
"""Most untied pairs tried for a stiffening edge (a team of 35; beyond, none is named)."""
_MAX_NEW_EDGES = 12


@dataclass(frozen=True)
class ShapeHold:
    """The shape's weakest mode and the distance error it lets a disturbance make."""

    stiffness: float
    """Smallest non-zero eigenvalue of ``R^T R`` (unit edge directions)."""
    disturbance: float
    """The unseen acceleration per vehicle assumed, m/s^2."""
    drift_error: float
    """Bound on the distance error that disturbance holds the shape at, m."""
    new_edges: tuple[tuple[int, int], ...]
    """Vehicle ids of edges that, added, bring the bound within the target (empty when it
    is already within, or when none were found)."""
    new_stiffness: float
    """The weakest mode's stiffness with those edges added."""


def _unit_rigidity(positions: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """(m, 2n) rigidity matrix of the horizontal shape, each row scaled to unit edge
    direction."""
    p = np.asarray(positions, dtype=float)[:, :2]
    lengths = np.linalg.norm(p[edges[:, 0]] - p[edges[:, 1]], axis=1)
    return rigidity_matrix(p, edges) / lengths[:, None]


def weakest_mode(positions: np.ndarray, edges: np.ndarray) -> float:
    """Stiffness of the weakest non-rigid deformation of a planar shape: the smallest
    eigenvalue of ``R^T R`` (unit edges) after the three rigid motions of the plane (two
    translations, one turn), which are its zeros."""
    R = _unit_rigidity(positions, edges)
    values = np.linalg.eigvalsh(R.T @ R)
    return float(max(values[min(3, len(values) - 1)], 0.0))


def drift_error(vehicles: int, c2: float, stiffness: float, disturbance: float) -> float:
    """Bound on the distance error, m: ``sqrt(n) a / (c2 sqrt(stiffness))`` (module doc)."""
    if stiffness <= 0.0:
        return math.inf
    return math.sqrt(vehicles) * disturbance / (c2 * math.sqrt(stiffness))


def stiffening_edges(positions: np.ndarray, edges: np.ndarray,
                     target: float) -> tuple[tuple[tuple[int, int], ...], float]:
    """Pairs of vehicles (team order) to tie so that the weakest stiffness reaches
    ``target``, chosen greedily (each the pair that stiffens most), and the stiffness
    reached; no pairs when the shape has too many untied pairs to search or no few
    edges reach it. A soft mode of a symmetric shape is several at once, so one edge
    rarely does (the ring of twelve needs three)."""
    n = len(positions)
    added: list[tuple[int, int]] = []
    current = np.asarray(edges, dtype=int)
    stiffness = weakest_mode(positions, current)
    while stiffness < target:
        tied = {frozenset((int(i), int(j))) for i, j in current}
        pairs = [(i, j) for i in range(n) for j in range(i + 1, n)
                 if frozenset((i, j)) not in tied]
        if not pairs or len(pairs) > _SEARCHED_PAIRS or len(added) == _MAX_NEW_EDGES:
            return (), weakest_mode(positions, edges)
        stiffness, pair = max((weakest_mode(positions, np.vstack([current, [p]])), p)
                              for p in pairs)
        added.append(pair)
        current = np.vstack([current, [pair]])
    return tuple(added), stiffness


def shape_hold(formation: Formation, c2: float, disturbance: float,
               within: float) -> ShapeHold:
    """The weakest mode of the desired shape, the distance error it allows, and the edges
    that would bring that error ``within`` the given bound, m."""
    stiffness = weakest_mode(formation.positions, formation.edges)
    drift = drift_error(formation.n, c2, stiffness, disturbance)
    if drift <= within or within <= 0.0:
        return ShapeHold(stiffness, disturbance, drift, (), stiffness)
    target = formation.n * (disturbance / (c2 * within)) ** 2
    pairs, reached = stiffening_edges(formation.positions, formation.edges, target)
    ids = formation.ids
    return ShapeHold(stiffness, disturbance, drift,
                     tuple((ids[i], ids[j]) for i, j in pairs), reached)
