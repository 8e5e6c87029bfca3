"""The payload hanging at rest from its ropes: where it hangs, which ropes pull, how hard.

Why: the paper's analysis assumes each vehicle carries a fixed share of the
payload (a third of it for the square). The real share follows from the
geometry: the payload hangs at the lowest point it can reach, and a rope is
taut or slack depending on where its vehicle is and how long it is. Four ropes
of one length from corners that are not on one circle leave two of them slack
and the other two carrying everything.

The model is the simulator's in the limit of stiff ropes (inextensible, massless,
pulling only): a point-mass payload under ``n`` anchor points (the vehicles'
centres of mass, NED) on ropes of given lengths.

* **Where it hangs**: the lowest point (largest NED z) of the intersection of the
  balls ``|p - a_i| <= L_i``, a small convex problem. It is LP-type: the optimum
  rests on at most three spheres (a basis), so :func:`hanging_point` adds the most
  violated rope to the basis until none is violated, each time solving the few-ball
  problem exactly (below a rope, at the bottom of two ropes' circle, or where three
  spheres meet); the hanging point rises strictly at each step, so it ends.
* **Which ropes pull**: those at full length at that point (within
  :data:`TAUT_TOLERANCE`); the others are slack.
* **How hard**: the tensions ``T >= 0`` with ``sum T_i u_i = M g e_down`` (``u_i``
  the unit vector from the vehicle to the payload). Three ropes or fewer fix them;
  more (four ropes to a square's centre) leave them statically indeterminate, and
  the limit of equally stiff ropes picks the split: the least ``sum T_i^2``, found as
  ``T_i = max(0, u_i . q)`` with ``q`` minimising a smooth convex function (Newton).
  That is what the simulator's equal ropes give with every vehicle exactly at its
  anchor; a millimetre of difference in height moves the split of such a team (see
  :func:`worst_share`).

A payload that accelerates with the team (:func:`accelerating_load`) is the same
problem in the team's frame, under the effective gravity ``g - a``.

A vehicle's load is its rope's pull on it: ``T_i u_i``, its vertical part the
weight it carries, its horizontal part eq. Th's pull.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations

import numpy as np

__all__ = ["TAUT_TOLERANCE", "NoHangingPointError", "StaticLoad", "accelerating_load",
           "hanging_point", "rope_tensions", "static_load"]

TAUT_TOLERANCE = 1e-6
"""A rope within this fraction of its length from full length counts as taut. Far below
the simulator's stretch under load (0.25 mm on a metre) and above the rounding of
positions given to six decimals (a regular hexagon's 0.866025)."""

_DOWN = np.array([0.0, 0.0, 1.0])
_EYE = np.eye(3)


def _norm(v: np.ndarray) -> float:
    """``np.linalg.norm(v)`` of a vector, the same operations without its overhead: the
    analysis takes tens of thousands of norms of 3-vectors, and numpy's per-call cost
    was most of its time (the square's analysis: 0.45 s with numpy's, 0.29 s with these)."""
    return math.sqrt(v.dot(v))


def _norms(d: np.ndarray) -> np.ndarray:
    """``np.linalg.norm(d, axis=1)``, the same operations without its overhead."""
    return np.sqrt(np.add.reduce(d * d, axis=1))


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross(a, b)`` of two 3-vectors, the same operations without its overhead."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


class NoHangingPointError(ValueError):
    """The ropes cannot all reach one point: no payload position holds every rope."""


@dataclass(frozen=True)
class StaticLoad:
    """The payload at rest under its ropes (NED, SI units); ``i`` is the vehicle's index."""

    payload_ned: np.ndarray
    """(3,) where the payload hangs, m."""
    tension: np.ndarray
    """(n,) rope tension, N (0 for a slack rope)."""
    taut: np.ndarray
    """(n,) bool, the rope is at full length."""
    force_ned: np.ndarray
    """(n, 3) the rope's pull on its vehicle, towards the payload, N."""
    weight: float
    """The payload's weight M g, N."""

    @property
    def vertical(self) -> np.ndarray:
        """(n,) downward pull on each vehicle: the part of the payload it carries, N."""
        return self.force_ned[:, 2]

    @property
    def horizontal(self) -> np.ndarray:
        """(n,) horizontal pull on each vehicle (eq. Th's T_h), N."""
        return np.hypot(self.force_ned[:, 0], self.force_ned[:, 1])

    @property
    def share(self) -> np.ndarray:
        """(n,) fraction of the payload's weight each vehicle carries."""
        return self.vertical / self.weight

    @property
    def rope_angle(self) -> np.ndarray:
        """(n,) each rope's angle from the vertical, rad."""
        return np.arctan2(self.horizontal, np.maximum(self.vertical, 0.0)) * self.taut


def _below_one(a: np.ndarray, length: float) -> np.ndarray:
    return a + length * _DOWN


def _below_two(a: np.ndarray, b: np.ndarray, la: float, lb: float) -> np.ndarray | None:
    """The lowest point of the circle where two spheres meet (None: they do not)."""
    axis = b - a
    d = _norm(axis)
    if d == 0.0 or d >= la + lb or d <= abs(la - lb):
        return None
    axis /= d
    t = (d * d + la * la - lb * lb) / (2.0 * d)
    radius = math.sqrt(max(la * la - t * t, 0.0))
    down = _DOWN - (_DOWN @ axis) * axis
    norm = _norm(down)
    if norm < 1e-12:  # one vertically above the other: the circle is level, any point does
        down = np.array([1.0, 0.0, 0.0]) - axis[0] * axis
        norm = _norm(down)
    return a + t * axis + radius * down / norm


def _below_three(a: np.ndarray, b: np.ndarray, c: np.ndarray, la: float, lb: float,
                 lc: float) -> np.ndarray | None:
    """The lower of the two points where three spheres meet (None: they do not)."""
    ex = b - a
    d = _norm(ex)
    if d == 0.0:
        return None
    ex /= d
    i = float(ex @ (c - a))
    ey = c - a - i * ex
    ny = _norm(ey)
    if ny < 1e-12 * max(d, 1.0):  # collinear centres: no isolated points
        return None
    ey /= ny
    ez = _cross(ex, ey)
    j = float(ey @ (c - a))
    x = (la * la - lb * lb + d * d) / (2.0 * d)
    y = (la * la - lc * lc + i * i + j * j - 2.0 * i * x) / (2.0 * j)
    zz = la * la - x * x - y * y
    if zz < 0.0:
        return None
    base = a + x * ex + y * ey
    z = math.sqrt(zz)
    p1, p2 = base + z * ez, base - z * ez
    return p1 if p1[2] >= p2[2] else p2


def _lowest(anchors: np.ndarray, lengths: np.ndarray,
            basis: tuple[int, ...]) -> tuple[np.ndarray, tuple[int, ...]]:
    """The lowest point of the balls in ``basis`` (at most four) and the ropes it rests on."""
    best: tuple[np.ndarray, tuple[int, ...]] | None = None
    rows = list(basis)
    held, reach_of, tolerance = anchors[rows], lengths[rows], 1e-9 * lengths[rows]
    for size in (1, 2, 3):
        for subset in combinations(basis, size):
            if size == 1:
                p: np.ndarray | None = _below_one(anchors[subset[0]], float(lengths[subset[0]]))
            elif size == 2:
                i, j = subset
                p = _below_two(anchors[i], anchors[j], lengths[i], lengths[j])
            else:
                i, j, k = subset
                p = _below_three(anchors[i], anchors[j], anchors[k], lengths[i], lengths[j],
                                 lengths[k])
            if p is None:
                continue
            reach = _norms(held - p) - reach_of
            if (reach <= tolerance).all() and (best is None or p[2] > best[0][2]):
                best = (p, subset)
    if best is None:
        raise NoHangingPointError(f"ropes {', '.join(str(i) for i in basis)} cannot all reach "
                             f"one point")
    return best


def hanging_point(anchors_ned: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Where a payload hangs from ropes of ``lengths`` (n,) tied to ``anchors_ned`` (n, 3).

    The lowest point that every rope reaches; raises :class:`NoHangingPointError` (a
    ValueError) when there is none.
    """
    anchors = np.asarray(anchors_ned, dtype=np.float64)
    lengths = np.asarray(lengths, dtype=np.float64)
    basis: tuple[int, ...] = (int(np.argmin(anchors[:, 2] + lengths)),)
    p = _below_one(anchors[basis[0]], float(lengths[basis[0]]))
    for _ in range(10 * len(lengths) + 10):
        excess = _norms(anchors - p) - lengths
        k = int(np.argmax(excess / lengths))
        if excess[k] <= 1e-9 * lengths[k]:
            return p
        p, basis = _lowest(anchors, lengths, (*basis, k))
    raise NoHangingPointError("the hanging point was not found")  # the proof says never


def rope_tensions(units: np.ndarray, weight: float) -> np.ndarray:
    """Tensions of taut ropes whose unit vectors vehicle -> payload are ``units`` (k, 3).

    The least-squares tensions ``T >= 0`` holding ``weight`` (N, straight down):
    ``T_i = max(0, u_i . q)`` with ``sum T_i u_i = weight e_down``, by Newton on
    ``phi(q) = sum max(0, u_i . q)^2 / 2 - weight q_z`` (convex, piecewise quadratic).
    """
    target = weight * _DOWN
    q = weight * _DOWN / max(float(np.sum(units[:, 2] ** 2)), 1e-12)
    for _ in range(100):
        s = units @ q
        on = s > 0.0
        grad = units[on].T @ s[on] - target
        if _norm(grad) <= 1e-12 * weight:
            break
        hess = units[on].T @ units[on] + 1e-12 * _EYE
        step = np.linalg.lstsq(hess, grad, rcond=None)[0]
        phi = 0.5 * float(np.sum(np.maximum(s, 0.0) ** 2)) - float(target @ q)
        t = 1.0
        while t > 1e-12:  # backtracking: the pieces change where a tension reaches zero
            trial = q - t * step
            st = units @ trial
            if 0.5 * float(np.sum(np.maximum(st, 0.0) ** 2)) - float(target @ trial) \
                    <= phi - 1e-4 * t * float(grad @ step):
                break
            t *= 0.5
        q = q - t * step
    return np.maximum(units @ q, 0.0)


def _elastic_point(anchors: np.ndarray, lengths: np.ndarray, weight: float, stiffness: float,
                   start: np.ndarray) -> np.ndarray:
    """Where the payload rests on ropes of ``stiffness`` N/m: the least of
    ``E(p) = -weight p_z + sum stiffness/2 max(0, |p - a_i| - L_i)^2`` (convex), by Newton from
    just below ``start`` (the stiff ropes' point)."""

    def energy(p: np.ndarray) -> float:
        stretch = np.maximum(_norms(p - anchors) - lengths, 0.0)
        return -weight * float(p[2]) + 0.5 * stiffness * float(stretch @ stretch)

    p = start + _DOWN * weight / stiffness
    for _ in range(100):
        d = p - anchors
        dist = _norms(d)
        stretch = np.maximum(dist - lengths, 0.0)
        on = stretch > 0.0
        u = d[on] / dist[on, None]
        grad = stiffness * (stretch[on, None] * u).sum(axis=0) - weight * _DOWN
        if _norm(grad) <= 1e-9 * weight:  # the point within ~1e-11 m
            break
        ratio = stretch[on] / dist[on]
        hess = stiffness * (u.T @ (u * (1.0 - ratio[:, None])) + ratio.sum() * _EYE)
        step = np.linalg.solve(hess + 1e-9 * stiffness * _EYE, grad)
        e0, t = energy(p), 1.0
        while t > 1e-12 and energy(p - t * step) > e0 - 1e-4 * t * float(grad @ step):
            t *= 0.5
        p = p - t * step
        if t * _norm(step) < 1e-13:  # no progress left but rounding's
            break
    return p


def static_load(anchors_ned: np.ndarray, lengths: np.ndarray, weight: float, *,
                stiffness: float | None = None) -> StaticLoad:
    """The payload of ``weight`` N at rest under ``anchors_ned`` (n, 3) on ropes ``lengths``.

    ``stiffness`` (N/m, the same for every rope): ropes that stretch, whose tension is
    ``stiffness`` times their stretch, which fixes the split of four or more taut ropes
    by how far each is stretched; None: stiff ropes (the limit), split by least squares.
    Raises :class:`NoHangingPointError` (a ValueError) when the ropes cannot all reach
    one point.
    """
    anchors = np.asarray(anchors_ned, dtype=np.float64)
    lengths = np.asarray(lengths, dtype=np.float64)
    p = hanging_point(anchors, lengths)
    tension = np.zeros(len(lengths))
    if stiffness is None:
        to_payload = p - anchors
        dist = _norms(to_payload)
        taut = dist >= lengths * (1.0 - TAUT_TOLERANCE)
        tension[taut] = rope_tensions(to_payload[taut] / dist[taut, None], weight)
    else:
        p = _elastic_point(anchors, lengths, weight, stiffness, p)
        to_payload = p - anchors
        dist = _norms(to_payload)
        tension = stiffness * np.maximum(dist - lengths, 0.0)
        taut = tension > 0.0
    force = tension[:, None] * to_payload / dist[:, None]
    return StaticLoad(payload_ned=p, tension=tension, taut=taut, force_ned=force, weight=weight)


def _turning_to_down(direction: np.ndarray) -> np.ndarray:
    """The rotation (3, 3) that turns the unit vector ``direction`` onto straight down."""
    axis = _cross(direction, _DOWN)
    sin, cos = _norm(axis), float(direction @ _DOWN)
    if sin < 1e-12:
        return np.eye(3)
    k = axis / sin
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return _EYE + sin * cross + (1.0 - cos) * cross @ cross


def accelerating_load(anchors_ned: np.ndarray, lengths: np.ndarray, mass: float,
                      gravity: float, accel_ned: np.ndarray) -> StaticLoad:
    """The payload of ``mass`` kg carried at a steady acceleration ``accel_ned`` (3,) m/s^2
    under ``anchors_ned`` (n, 3) that move with it, on ropes ``lengths`` (stiff ropes).

    Why: in flight the payload accelerates with the team, and its ropes then hold
    ``M (g - a)`` rather than its weight: it swings back until it hangs along that
    effective gravity, and the ropes on the side it accelerates towards carry more of
    it. In the team's accelerating frame this is the payload at rest under a tilted
    gravity, so it is :func:`static_load` with the anchors turned until the effective
    gravity points down, turned back. The result is in the world frame, and ``weight``
    is the payload's true weight ``M g``: ``share`` is the part of the weight each
    vehicle carries, what a vehicle's thrust must hold up (it can exceed the share at
    rest). Raises :class:`NoHangingPointError` as :func:`static_load`.
    """
    effective = np.array([0.0, 0.0, gravity]) - np.asarray(accel_ned, dtype=np.float64)
    g_eff = float(np.linalg.norm(effective))
    turn = _turning_to_down(effective / g_eff)
    held = static_load(np.asarray(anchors_ned, dtype=np.float64) @ turn.T, lengths,
                       mass * g_eff)
    return StaticLoad(payload_ned=turn.T @ held.payload_ned, tension=held.tension,
                      taut=held.taut, force_ned=held.force_ned @ turn, weight=mass * gravity)
