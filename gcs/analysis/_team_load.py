"""The payload's load on each vehicle of a team: at its desired shape, at the worst shape
within a deformation, and the rope lengths that make every rope taut.

Why: the paper lets a vehicle carry a fixed share of the payload (1/(n-1)); the
geometry decides it (:mod:`gcs.analysis._static_load`). A team's vehicles hover at
one altitude on their desired shape, so their rope anchors are the shape's positions
at z = 0 (NED), the payload hanging below.

* :func:`desired_load`: the payload at rest under the desired shape, with the
  team's rope lengths; which ropes are slack, each vehicle's tension and share.
* :func:`worst_load`: the largest share of any vehicle over shapes whose vehicles
  are each at most ``deformation`` metres (horizontally) off their desired place:
  seeded samples of the extreme displacements, then a local search from the worst.
  With four or more taut ropes the split is statically indeterminate, and with stiff
  ropes a millimetre decides it: the worst case is then the worst set of two or three
  ropes carrying everything, reached by arbitrarily small deformations. In the
  simulator the vehicles' position holds give by millimetres under load and soften
  this: one vehicle of the paper's square 5 mm, 2 cm, 5 cm and 8 cm in from its corner
  puts 0.262, 0.308, 0.412 and 0.480 of the payload on each vehicle of the opposite
  diagonal (rigid ropes: 0.5 at any distance).
* :func:`accelerating_share`: the largest share of any vehicle while the payload
  accelerates horizontally with the team (up to the guidance's acceleration limit, in
  any direction): the ropes then hold ``M (g - a)``, and the ropes on the side it
  accelerates towards carry more of its weight than at rest.
* :func:`even_rope_lengths`: ropes that hang the payload under the centroid, every
  rope taut (the even share's place: with the vehicles at one altitude the payload's
  horizontal balance puts it there), none steeper than the design rope angle.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from gcs.analysis._static_load import (
    NoHangingPointError,
    StaticLoad,
    accelerating_load,
    static_load,
)
from gcs.config import Team

__all__ = ["AcceleratingShare", "WorstLoad", "accelerating_share", "desired_load",
           "even_rope_lengths", "hang_depth", "worst_load"]

_SAMPLES = 96
"""Random displacements tried by :func:`worst_load` (before it climbs)."""
_CLIMBS = 6
"""Gradient steps of :func:`worst_load`'s climb, at most."""


def _anchors(xy: np.ndarray) -> np.ndarray:
    return np.column_stack([xy, np.zeros(len(xy))])


def _ropes(team: Team) -> np.ndarray:
    return np.asarray(team.config.payload.lengths(team.formation.n), dtype=np.float64)


def _weight(team: Team) -> float:
    return team.config.payload.mass * team.config.analysis.gravity


def desired_load(team: Team, *, scale: float = 1.0) -> StaticLoad:
    """The payload at rest under the team's desired shape (times ``scale``), NED about the
    centroid at the vehicles' altitude."""
    return static_load(_anchors(scale * team.formation.positions), _ropes(team), _weight(team))


def hang_depth(team: Team, *, scale: float = 1.0) -> float:
    """How far below the vehicles the payload hangs at the desired shape (times ``scale``):
    the vehicles' altitude at which it leaves the ground, m."""
    return float(desired_load(team, scale=scale).payload_ned[2])


@dataclass(frozen=True)
class WorstLoad:
    """The largest share of the payload one vehicle carries over the displaced anchors."""

    share: float
    """Fraction of the payload's weight on the most loaded vehicle."""
    vehicle: int
    """Its index in team order."""
    tension: float
    """The largest rope tension over the displacements tried, N."""
    horizontal: float
    """The largest horizontal rope pull on a vehicle over the displacements tried, N."""
    error: float
    """The bound on each vehicle's displacement (3-D), m."""
    anchors_ned: np.ndarray
    """(n, 3) the anchors that give ``share``, m."""
    tried: int


def worst_load(team: Team, error: float, *, stiffness: float, seed: int = 0,
               scale: float = 1.0) -> WorstLoad:
    """The worst share with each vehicle anywhere within ``error`` m (3-D) of its place at
    the desired shape (times ``scale``), the payload at rest on ropes of effective
    ``stiffness`` N/m.

    Deterministic for a given ``seed``. Displacements at the bound are sampled (moving a
    vehicle away from the payload tightens its rope, towards it slackens it): each vehicle
    alone up, down, in and out, all but one up or down, and seeded random ones. Then the
    most loaded vehicle's share is climbed: every vehicle moves to the bound along the
    gradient of that share (finite differences), while that gains.
    """
    base = _anchors(scale * np.asarray(team.formation.positions, dtype=np.float64))
    n = len(base)
    ropes, weight = _ropes(team), _weight(team)
    best_share, best_vehicle, best = -1.0, 0, base
    tension = horizontal = 0.0
    tried = 0

    def load_of(anchors: np.ndarray) -> np.ndarray | None:
        nonlocal best_share, best_vehicle, best, tension, horizontal, tried
        try:
            s = static_load(anchors, ropes, weight, stiffness=stiffness)
        except ValueError:  # the ropes cannot reach one point: not a place to hang from
            return None
        tried += 1
        tension = max(tension, float(s.tension.max()))
        horizontal = max(horizontal, float(s.horizontal.max()))
        if float(s.share.max()) > best_share:
            best_share, best_vehicle, best = float(s.share.max()), int(np.argmax(s.share)), anchors
        return s.share

    load_of(base)
    if error <= 0.0:
        return WorstLoad(best_share, best_vehicle, tension, horizontal, 0.0, best, tried)
    up = np.array([0.0, 0.0, -1.0])
    radial = base / np.maximum(np.linalg.norm(base, axis=1, keepdims=True), 1e-12)
    for k in range(n):
        for step in (up, -up, radial[k], -radial[k]):
            moved = base.copy()
            moved[k] += error * step
            load_of(moved)
        for sign in (-1.0, 1.0):  # everyone up (or down) but one
            moved = base + sign * error * up
            moved[k] = base[k]
            load_of(moved)
    rng = np.random.default_rng(seed)
    for _ in range(_SAMPLES):
        step = rng.normal(size=(n, 3))
        step *= error / np.linalg.norm(step, axis=1, keepdims=True)
        step[rng.random(n) < 0.25] = 0.0
        load_of(base + step)

    w, h = best_vehicle, 1e-3 * error  # climb the most loaded vehicle's share
    centre, value = best - base, best_share
    for _ in range(_CLIMBS):
        grad = np.zeros((n, 3))
        for k in range(n):
            for axis in range(3):
                moved = centre.copy()
                moved[k, axis] += h
                share = load_of(base + moved)
                grad[k, axis] = 0.0 if share is None else (share[w] - value) / h
        scale = error / max(float(np.linalg.norm(grad, axis=1).max()), 1e-300)
        for _ in range(4):  # projected step, halved until it gains
            step = centre + scale * grad
            norm = np.linalg.norm(step, axis=1, keepdims=True)
            step *= np.minimum(1.0, error / np.maximum(norm, 1e-300))
            share = load_of(base + step)
            if share is not None and share[w] > value + 1e-9:
                centre, value = step, float(share[w])
                break
            scale *= 0.5
        else:
            break
    return WorstLoad(best_share, best_vehicle, tension, horizontal, error, best, tried)


@dataclass(frozen=True)
class AcceleratingShare:
    """The most any vehicle carries while the payload accelerates horizontally."""

    accel: float
    """The payload's horizontal acceleration, m/s^2."""
    share: float
    """Largest fraction of the payload's weight on one vehicle, over the directions and
    scales tried."""
    vehicle: int
    """Its index in team order."""
    direction: float
    """Direction of the acceleration that gives it, rad from the team's x axis."""
    tension: float
    """The largest rope tension over the directions and scales tried, N."""


_DIRECTIONS = 72
"""Directions of the horizontal acceleration tried (every 5 degrees)."""


def accelerating_share(team: Team, accel: float, scales: tuple[float, ...] = (1.0,),
                       directions: np.ndarray | None = None) -> AcceleratingShare:
    """The largest share of the payload on one vehicle, and the largest rope tension, with
    the payload accelerating at ``accel`` m/s^2 in any horizontal direction (every 5
    degrees around the worst of every 15, or ``directions``, rad; stiff ropes, the desired
    shape times each of ``scales``; a scale whose ropes cannot hang the payload is
    skipped). The payload's share at rest when ``accel`` is 0."""
    mass, g = team.config.payload.mass, team.config.analysis.gravity
    ropes = _ropes(team)
    best = AcceleratingShare(accel, -1.0, 0, 0.0, 0.0)
    tension = 0.0
    for scale in scales:
        anchors = _anchors(scale * np.asarray(team.formation.positions, dtype=np.float64))

        def held_at(psi: float) -> tuple[float, int, float] | None:
            """(largest share, its vehicle, largest tension) accelerating towards ``psi``."""
            a = accel * np.array([math.cos(psi), math.sin(psi), 0.0])
            try:
                held = accelerating_load(anchors, ropes, mass, g, a)  # noqa: B023
            except ValueError:  # the ropes cannot reach one point at this scale
                return None
            return float(held.share.max()), int(np.argmax(held.share)), float(held.tension.max())

        if accel <= 0.0:
            tried = np.zeros(1)
        elif directions is not None:
            tried = np.asarray(directions, dtype=np.float64)
        else:
            tried = np.linspace(0.0, 2.0 * math.pi, _DIRECTIONS // 3, endpoint=False)
        found = {float(psi): held_at(float(psi)) for psi in tried}
        coarse = {psi: h for psi, h in found.items() if h is not None}
        if directions is None and accel > 0.0 and coarse:
            tops = {max(coarse, key=lambda p: coarse[p][0]),
                    max(coarse, key=lambda p: coarse[p][2])}
            step = 2.0 * math.pi / _DIRECTIONS
            for top in tops:  # the every-5-degree directions next to the worst of every 15
                for k in (-2, -1, 1, 2):
                    found.setdefault(top + k * step, held_at(top + k * step))
        for psi, h in found.items():
            if h is None:
                continue
            tension = max(tension, h[2])
            if h[0] > best.share:
                best = AcceleratingShare(accel, h[0], h[1], psi % (2.0 * math.pi), 0.0)
    if best.share < 0.0:
        raise NoHangingPointError("the ropes cannot hang the payload at any scale tried")
    return dataclasses.replace(best, tension=tension)


def even_rope_lengths(team: Team) -> np.ndarray:
    """Rope lengths (team order, m) that hang the payload under the centroid, every rope taut.

    With the vehicles at one altitude, equal vertical shares balance horizontally only with
    the payload under the centroid, so every rope reaches exactly that point. The depth is
    the payload's with the configured ropes, or deeper where a rope would otherwise lean
    more than ``analysis.design_rope_angle_deg``.
    """
    radii = team.formation.radii
    steepest = math.radians(team.config.analysis.design_rope_angle_deg)
    depth = max(hang_depth(team), float(radii.max()) / math.tan(steepest))
    return np.sqrt(depth**2 + radii**2)
