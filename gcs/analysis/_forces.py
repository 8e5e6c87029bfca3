"""The paper's force chain (eq. T, Th and the largest acceleration) for one payload share.

* the vertical load ``(m + M share) g``, the largest tilt
  ``arccos(load / thrust_reference)`` and the horizontal force left at the bank
  limit ``thrust_reference * sin(bank)``;
* eq. Th as written, ``T_h = (M g / share) ||z2|| / (2 sqrt(l^2 - ||z2||^2 / 4))``
  where ``||z2||`` is the distance between two vehicles on opposite sides of the
  payload (twice the vehicle's distance to the centroid). It equals
  ``(M g / share) tan(rope angle)``, so the paper's bound ``M g / 3`` holds where
  the rope is at 45 degrees, ``||z2|| = l sqrt 2`` (1.58 m for the paper's team),
  and not at the 2 m the paper's prose names, where the equation gives twice it.
  The design point is the configured rope angle (``analysis.design_rope_angle_deg``);
  the report also shows eq. Th at the nominal shape and at eq. max's worst edge;
* the largest guidance acceleration ``(F_h - T_h) / m`` and its per-axis limit
  (the same vector at 45 degrees to both axes);
* the largest deformation of the team that still leaves the configured largest
  commanded acceleration available: the rope pull grows with the distance from
  vehicle to payload, so ``F_h - T_h(r) >= m a_max`` bounds r.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gcs.config import Team, TeamConfig

__all__ = ["AXIS_FACTOR", "Chain", "RopePulls", "a_safe_span", "chain", "rope_pull",
           "rope_pulls", "vertical_load"]

AXIS_FACTOR = math.sin(math.pi / 4)
"""Direction of the worst acceleration vector: 45 degrees to both axes (paper)."""


def vertical_load(cfg: TeamConfig, share: float, mass: float) -> float:
    """The vertical load on one vehicle carrying ``share`` of a ``mass`` kg payload, N."""
    return (cfg.airframe.mass + mass * share) * cfg.analysis.gravity


def rope_pull(weight_share: float, rope_length: float, span: float) -> float:
    """Eq. Th: horizontal rope pull on a vehicle whose opposite neighbour is ``span`` away.

    Returns inf when the rope cannot reach (span >= 2 l).
    """
    half = 0.5 * span
    if half >= rope_length:
        return math.inf
    return weight_share * half / math.sqrt(rope_length**2 - half**2)


def a_safe_span(horizontal_force: float, mass: float, accel: float, weight_share: float,
                rope_length: float) -> float:
    """Largest span (eq. Th's ||z2||) whose rope pull still leaves ``accel`` available, m.

    ``F_h - T_h(span) >= m accel`` with ``T_h = weight_share tan(rope angle)``;
    0 when even a vertical rope leaves too little.
    """
    spare = horizontal_force - mass * accel
    if spare <= 0:
        return 0.0
    return 2.0 * rope_length * math.sin(math.atan(spare / weight_share))


@dataclass(frozen=True)
class Chain:
    """The paper's force chain for one payload mass and design share (SI units)."""

    load: float
    max_tilt: float
    horizontal_force: float
    weight_share: float
    rope_pull_design: float
    max_accel: float
    max_axis: float
    safe_span: float
    safe_margin: float


def chain(team: Team, mass: float, share: float) -> Chain:
    """Eq. T / Th's chain: vertical load, largest tilt, horizontal force, rope pull at the
    design angle, largest acceleration and the safe span, for ``mass`` kg carried at
    ``share`` of its weight per vehicle."""
    cfg = team.config
    g, m = cfg.analysis.gravity, cfg.airframe.mass
    load = vertical_load(cfg, share, mass)
    thrust_ref = cfg.airframe.thrust_reference
    max_tilt = math.acos(load / thrust_ref) if load < thrust_ref else 0.0
    f_h = thrust_ref * math.sin(cfg.limits.bank)
    weight_share = mass * g * share
    theta = math.radians(cfg.analysis.design_rope_angle_deg)
    rope = min(cfg.payload.lengths(team.formation.n))
    t_design = rope_pull(weight_share, rope, 2.0 * rope * math.sin(theta))
    max_accel = (f_h - t_design) / m
    safe_span = a_safe_span(f_h, m, cfg.limits.accel_norm, weight_share, rope)
    return Chain(load=load, max_tilt=max_tilt, horizontal_force=f_h, weight_share=weight_share,
                 rope_pull_design=t_design, max_accel=max_accel,
                 max_axis=max_accel * AXIS_FACTOR, safe_span=safe_span,
                 safe_margin=safe_span - 2.0 * float(team.formation.radii.max()))


@dataclass(frozen=True)
class RopePulls:
    """Eq. Th at the shapes the certificate shows (spans in m, pulls in N)."""

    nominal_span: float
    nominal: float
    design_angle: float
    """The design rope angle from vertical, rad."""
    design_span: float
    bound_span: float
    """Where the pull is the weight share itself (the rope at 45 degrees): ``l sqrt 2``."""
    worst_edge: float
    at_worst_edge: float


def rope_pulls(team: Team, weight_share: float, worst_edge: float) -> RopePulls:
    """Eq. Th at the nominal shape, the design angle's span, the 45 degrees bound and eq.
    max's ``worst_edge``, with the shortest rope and ``weight_share`` N per vehicle."""
    cfg = team.config
    rope = min(cfg.payload.lengths(team.formation.n))
    nominal_span = 2 * float(team.formation.radii.max())
    theta = math.radians(cfg.analysis.design_rope_angle_deg)
    return RopePulls(nominal_span=nominal_span,
                     nominal=rope_pull(weight_share, rope, nominal_span),
                     design_angle=theta, design_span=2.0 * rope * math.sin(theta),
                     bound_span=rope * math.sqrt(2.0), worst_edge=worst_edge,
                     at_worst_edge=rope_pull(weight_share, rope, worst_edge))
