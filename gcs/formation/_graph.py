"""Rigid formation model: graph, desired shape, incidence and rigidity.

The team's desired shape is a framework: vehicle positions in the team's body
frame (x forward, y right, metres) and an undirected edge list, each edge
``k = (tail, head)`` with ``z_k = p_tail - p_head`` (paper, eq. ``B``).
Guidance only works for infinitesimally rigid frameworks (rank of the rigidity
matrix ``2n - 3``): a flexible one has motions that change the shape without
changing any controlled distance, so it is refused here, once, at load time.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gcs.common import kernel

__all__ = [
    "Formation",
    "FormationError",
    "build_formation",
    "incidence_matrix",
    "is_infinitesimally_rigid",
    "realize_positions",
    "rigidity_matrix",
]

#: Relative tolerance for "the distances fit the positions".
DISTANCE_TOLERANCE = 1e-3


class FormationError(ValueError):
    """A shape that cannot be flown; ``where`` names the offending config entry."""

    def __init__(self, where: str, what: str) -> None:
        self.where = where
        self.what = what
        super().__init__(f"{where}: {what}")


def incidence_matrix(n: int, edges: np.ndarray) -> np.ndarray:
    """Incidence matrix B (n, m): +1 at the tail, -1 at the head of each edge."""
    m = len(edges)
    B = np.zeros((n, m))
    B[edges[:, 0], np.arange(m)] = 1.0
    B[edges[:, 1], np.arange(m)] = -1.0
    return B


def rigidity_matrix(positions: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Rigidity matrix R (m, 2n): row k is z_k^T at the tail and -z_k^T at the head."""
    n = len(positions)
    z = positions[edges[:, 0]] - positions[edges[:, 1]]
    R = np.zeros((len(edges), 2 * n))
    for k, (i, j) in enumerate(edges):
        R[k, 2 * i : 2 * i + 2] = z[k]
        R[k, 2 * j : 2 * j + 2] = -z[k]
    return R


def is_infinitesimally_rigid(positions: np.ndarray, edges: np.ndarray) -> bool:
    """True when rank R = 2n - 3 (for n >= 2), i.e. only rigid motions keep all distances."""
    n = len(positions)
    if n < 2 or len(edges) == 0:
        return False
    R = rigidity_matrix(positions, edges)
    scale = max(float(np.abs(R).max()), 1e-12)
    return int(np.linalg.matrix_rank(R / scale, tol=1e-8)) == 2 * n - 3


def realize_positions(n: int, edges: np.ndarray, distances: np.ndarray) -> np.ndarray:
    """Planar positions whose edge lengths are ``distances``, centred on their centroid.

    Deterministic: least squares from a few regular-polygon starts (with and without
    a reflection); the best fit is returned and the caller checks the residual.
    """
    # imported here: scipy.optimize is 0.45 s of every process's start, and a team given
    # by its positions (every shipped one) never fits
    from scipy.optimize import least_squares

    best: np.ndarray | None = None
    best_cost = np.inf
    angles = 2.0 * np.pi * np.arange(n) / n
    radius = float(np.mean(distances)) / (2.0 * np.sin(np.pi / n)) if n > 1 else 1.0
    for order in (np.arange(n), np.arange(n)[::-1]):
        for twist in (0.0, 0.37, 1.1):
            start = radius * np.column_stack((np.cos(angles + twist * np.arange(n)),
                                              np.sin(angles + twist * np.arange(n))))[order]

            def residual(x: np.ndarray) -> np.ndarray:
                p = x.reshape(n, 2)
                return np.linalg.norm(p[edges[:, 0]] - p[edges[:, 1]], axis=1) - distances

            fit = least_squares(residual, start.ravel(), xtol=1e-14, ftol=1e-14, gtol=1e-14)
            if fit.cost < best_cost:
                best_cost, best = fit.cost, fit.x.reshape(n, 2)
    assert best is not None
    return best - best.mean(axis=0)


@dataclass(frozen=True, eq=False)
class Formation:
    """A desired rigid shape with its graph, ready for guidance.

    ``positions`` are centred on the centroid (the payload's place). The neighbour
    table gives each vehicle its incident edges as *slots* so that per-vehicle
    kernels never touch absolute positions: ``slot_neighbour[i, s]`` is the
    neighbour index, ``slot_edge[i, s]`` the edge, ``slot_sign[i, s]`` is +1 when
    ``i`` is the edge's tail (so ``p_i - p_j = slot_sign * z_k``); unused slots are
    masked out by ``slot_mask``.
    """

    ids: tuple[int, ...]
    positions: np.ndarray
    edges: np.ndarray
    distances: np.ndarray
    incidence: np.ndarray
    slot_neighbour: np.ndarray
    slot_edge: np.ndarray
    slot_sign: np.ndarray
    slot_mask: np.ndarray

    @property
    def n(self) -> int:
        """Number of vehicles."""
        return len(self.ids)

    @property
    def m(self) -> int:
        """Number of edges."""
        return len(self.edges)

    @property
    def radii(self) -> np.ndarray:
        """Horizontal distance of each vehicle from the centroid, m (n,)."""
        return np.linalg.norm(self.positions, axis=1)

    def relative(self, positions: np.ndarray) -> np.ndarray:
        """Edge vectors z = (B^T kron I2) p for stacked positions (n, 2) -> (m, 2)."""
        return positions[self.edges[:, 0]] - positions[self.edges[:, 1]]

    def distance_errors(self, positions: np.ndarray, scale: float = 1.0) -> np.ndarray:
        """e_k = ||z_k|| - scale * d_k for actual positions (n, 2) -> (m,).

        Compiled (:func:`edge_errors`): the loop computes them every tick, where
        the five numpy calls this takes otherwise each pay numpy's cost per call
        after its pause (figures: docs/performance.md, bench/gcs_tick.py).
        """
        return edge_errors(np.asarray(positions, dtype=float), self.edges, self.distances,
                           float(scale))

    def label(self, k: int) -> str:
        """Human-readable edge name, e.g. ``2-4``, with vehicle ids."""
        i, j = self.edges[k]
        return f"{self.ids[i]}-{self.ids[j]}"


@kernel()
def edge_errors(positions: np.ndarray, edges: np.ndarray, distances: np.ndarray,
                scale: float) -> np.ndarray:
    """||p_i - p_j|| - scale * d_k for each edge k = (i, j); positions (n, 2) -> (m,)."""
    out = np.empty(len(edges))
    for k in range(len(edges)):
        i, j = edges[k, 0], edges[k, 1]
        dx, dy = positions[i, 0] - positions[j, 0], positions[i, 1] - positions[j, 1]
        out[k] = math.sqrt(dx * dx + dy * dy) - scale * distances[k]  # NaN in: NaN out
    return out


def _why_not_rigid(positions: np.ndarray, edges: np.ndarray) -> str:
    """Why a shape is flexible, and the remedy: more edges, or a shape off a line.

    When even the complete graph on these positions is flexible, no edge helps:
    the geometry is degenerate (in the plane, all vehicles on one line).
    """
    n = len(positions)
    rank = int(np.linalg.matrix_rank(rigidity_matrix(positions, edges), tol=1e-8))
    need = f"rigidity matrix rank {rank}, needs {2 * n - 3}"
    complete = np.array([(i, j) for i in range(n) for j in range(i + 1, n)], dtype=np.int64)
    if is_infinitesimally_rigid(positions, complete):
        return f"the graph is not rigid: {need} (add edges)"
    return (f"the shape is degenerate: the vehicles are collinear, so no choice of edges "
            f"makes it rigid ({need}); place them off a line")


def build_formation(
    ids: Sequence[int],
    edges_by_id: Sequence[tuple[int, int]],
    *,
    positions: np.ndarray | None = None,
    distances: Sequence[float | None] | None = None,
) -> Formation:
    """Validate a shape and build its Formation.

    Either ``positions`` (n, 2) are given (distances, where given, must match them)
    or every edge has a distance and positions are realised from them.
    Raises FormationError naming the config entry at fault.
    """
    ids = tuple(int(i) for i in ids)
    n = len(ids)
    if len(set(ids)) != n:
        dup = next(i for i in ids if ids.count(i) > 1)
        raise FormationError("vehicles", f"vehicle id {dup} appears twice")
    index = {vid: i for i, vid in enumerate(ids)}
    edges = np.zeros((len(edges_by_id), 2), dtype=np.int64)
    seen: set[frozenset[int]] = set()
    for k, (tail, head) in enumerate(edges_by_id):
        for end, vid in (("tail", tail), ("head", head)):
            if vid not in index:
                raise FormationError(f"edges[{k}].{end}", f"unknown vehicle id {vid} "
                                     f"(vehicles: {', '.join(map(str, ids))})")
        if tail == head:
            raise FormationError(f"edges[{k}]", f"edge joins vehicle {tail} to itself")
        key = frozenset((tail, head))
        if key in seen:
            raise FormationError(f"edges[{k}]", f"edge {tail}-{head} is listed twice")
        seen.add(key)
        edges[k] = (index[tail], index[head])
    given = list(distances) if distances is not None else [None] * len(edges)

    if positions is None:
        missing = [k for k, dk in enumerate(given) if dk is None]
        if missing:
            raise FormationError(f"edges[{missing[0]}].distance",
                                 "missing: give vehicle positions or a distance for every edge")
        d = np.asarray(given, dtype=float)
        p = realize_positions(n, edges, d)
        fit = np.linalg.norm(p[edges[:, 0]] - p[edges[:, 1]], axis=1)
        bad = int(np.argmax(np.abs(fit - d) / d))
        if abs(fit[bad] - d[bad]) > DISTANCE_TOLERANCE * d[bad]:
            raise FormationError(f"edges[{bad}].distance",
                                 f"the distances cannot be realised in the plane "
                                 f"(best fit gives {fit[bad]:.3f} m for {d[bad]:.3f} m)")
    else:
        p = np.asarray(positions, dtype=float).reshape(n, 2)
        d = np.linalg.norm(p[edges[:, 0]] - p[edges[:, 1]], axis=1)
        for k, dk in enumerate(given):
            if dk is not None and abs(dk - d[k]) > DISTANCE_TOLERANCE * max(d[k], 1e-9):
                raise FormationError(f"edges[{k}].distance",
                                     f"{dk:g} m does not fit the positions of vehicles "
                                     f"{ids[edges[k, 0]]} and {ids[edges[k, 1]]} "
                                     f"({d[k]:.4g} m apart)")
        if np.any(d <= 1e-6):
            k = int(np.argmin(d))
            raise FormationError(f"edges[{k}]", "the two vehicles have the same position")
        p = p - p.mean(axis=0)

    if not is_infinitesimally_rigid(p, edges):
        raise FormationError("edges", _why_not_rigid(p, edges))

    slots = max(int(np.sum(edges == i)) for i in range(n))
    nb = np.zeros((n, slots), dtype=np.int64)
    ed = np.zeros((n, slots), dtype=np.int64)
    sg = np.zeros((n, slots))
    mk = np.zeros((n, slots), dtype=bool)
    fill = np.zeros(n, dtype=np.int64)
    for k, (i, j) in enumerate(edges):
        for me, other, sign in ((i, j, 1.0), (j, i, -1.0)):
            s = fill[me]
            nb[me, s], ed[me, s], sg[me, s], mk[me, s] = other, k, sign, True
            fill[me] += 1
    return Formation(ids=ids, positions=p, edges=edges, distances=d,
                     incidence=incidence_matrix(n, edges), slot_neighbour=nb, slot_edge=ed,
                     slot_sign=sg, slot_mask=mk)
