"""Force and worst-case analysis of a team (paper, section "Force and worst case").

Everything is computed from the team config with the paper's formulas,
generalised from the square to any rigid team, with the payload's share per
vehicle taken from the geometry (:mod:`gcs.analysis._team_load`):

* the static load at the desired shape: where the payload hangs under the team's
  rope lengths, which ropes are slack, each rope's tension (eq. T is the largest:
  ``(M g / n) l / sqrt(l^2 - r^2)`` when the payload hangs under the centroid of a
  regular team) and each vehicle's share of the payload;
* the design share: the larger of the paper's assumption (1/(n - 1), a third for
  four vehicles; ``analysis.payload_share``) and the largest share at rest. The
  paper's square keeps its third (a quarter at rest), a kite with two slack ropes
  gets the half its two taut ropes carry;
* the vertical load ``(m + M share) g``, the largest tilt
  ``arccos(load / thrust_reference)`` and the horizontal force left at the bank
  limit ``thrust_reference * sin(bank)``;
* the share with the payload accelerating with the team at ``limits.accel_norm`` in
  any direction: its ropes then hold ``M (g - a)``, more of it on the side it
  accelerates towards (a warning, naming the acceleration limit that keeps it within
  the design share, when it exceeds that share);
* the worst share with the vehicles anywhere within ``analysis.position_error`` of
  their places (ropes that give by ``analysis.hold_stiffness``, as the simulator's
  position holds do): a violation when a vehicle cannot hold it at full thrust, a
  warning with its figures when it exceeds the design share;
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
* the left side of eq. max, ``c1 ||e_v|| + c2 e_max kappa + mu_r ||z||_max`` with
  kappa the largest sum, over one vehicle's edges, of their unit vectors'
  components along a team axis (1 + 0.7 for the square) and ``||z||_max`` the
  longest edge carrying rotation disagreement, stretched by ``e_max``; when it
  fails, the gains that alone restore it are named with the value each needs
  (:func:`gain_violation` says why not the largest term);
* the largest deformation of the team that still leaves the configured largest
  commanded acceleration available: the rope pull grows with the distance from
  vehicle to payload, so F_h - T_h(r) >= m a_max bounds r;
* the largest payload the team can carry (bisection on the mass, the shares being
  the geometry's), named as a fix wherever the payload breaks a condition: no fix
  is ever a negative limit or bank angle;
* the lift: the altitude where the payload leaves the ground (at the smallest
  scale) plus the lift height, under ``operator.altitude_max`` and the geofence;
* the shape's weakest deformation mode (:mod:`gcs.analysis._shape_hold`): the distance
  error an unseen ``analysis.disturbance_accel`` per vehicle holds it at, within the
  safe deformation, or the distance gain and the edges that bring it there.
"""

from __future__ import annotations

import collections
import dataclasses
import json
import math
import threading
from dataclasses import asdict, dataclass, field
from typing import NamedTuple

import numpy as np

from gcs.analysis._shape_hold import ShapeHold, shape_hold
from gcs.analysis._static_load import NoHangingPointError
from gcs.analysis._team_load import (
    WorstLoad,
    accelerating_share,
    desired_load,
    even_rope_lengths,
    hang_depth,
    worst_load,
)
from gcs.config import Team, TeamConfig
from gcs.formation import motion_basis

__all__ = ["GAIN_FIELDS", "Analysis", "StaticShares", "Violation", "a_safe_span", "analysis_json",
           "analyze", "format_report", "gain_violation", "largest_payload", "rope_pull"]

#: Direction of the worst acceleration vector: 45 degrees to both axes (paper).
_AXIS_FACTOR = math.sin(math.pi / 4)


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
class Violation:
    """A condition of the analysis that the config breaks.

    ``term`` names the config field(s) at fault; ``fixes`` maps each field that
    alone restores the condition to the value it needs (the message says on
    which side: at most, or below).
    """

    term: str
    message: str
    fixes: dict[str, float] = field(default_factory=dict)


#: The config field behind each term of eq. max.
GAIN_FIELDS = {"c1_speed": "guidance.c1", "c2_distance": "guidance.c2",
               "mu_rotation": "guidance.max_rotation_disagreement"}


def gain_violation(terms: dict[str, float], per_unit: dict[str, float],
                   limit: float) -> Violation:
    """Eq. max broken: name the gains that alone restore it, with the value each needs.

    The left side is a sum, and the analysis has no budget per term to say which
    one grew: the largest term is often the nominal one (c2's for the paper's
    square), so naming it blamed c2 when c1 was raised. An operator can act on
    what is named here instead: every gain whose term exceeds the excess, with
    the largest value that fixes the condition if only that gain changes
    (``per_unit[key]`` is the term per unit of its gain); when no gain can do it
    alone, all three are named, to be reduced together.
    """
    lhs = sum(terms.values())
    excess = lhs - limit
    fixes = {GAIN_FIELDS[k]: (t - excess) / per_unit[k] for k, t in terms.items()
             if t > excess and per_unit[k] > 0}
    shown = " + ".join(f"{k} {_n(t)}" for k, t in terms.items())
    head = (f"gain condition (eq. max) violated: {shown} = {_n(lhs)} > {_n(limit)} m/s^2 "
            f"by {_n(excess)}")
    if not fixes:
        return Violation(" and ".join(GAIN_FIELDS.values()),
                         f"{head}; no gain alone can restore it: reduce several")
    alone = " or ".join(f"{name} <= {_floor3(v)}" for name, v in fixes.items())
    cannot = [f"{GAIN_FIELDS[k]} (term {_n(t)})" for k, t in terms.items()
              if GAIN_FIELDS[k] not in fixes]
    tail = f"; alone, not {', '.join(cannot)}" if cannot else ""
    return Violation(" or ".join(fixes), f"{head}; restored by {alone}{tail}", fixes)


def _floor3(x: float) -> str:
    """A bound printed to 3 decimals on its safe side (rounded down); %g beyond 1e5."""
    if not abs(x) < 1e5:
        return _n(x)
    return f"{math.floor(x * 1000.0) / 1000.0:.3f}"


def _n(x: float, digits: int = 3) -> str:
    """A number in a message: ``digits`` decimals, or 4 significant digits (%g) when it is
    too large for that to stay short (1e300 would print 300 digits)."""
    return f"{x:.{digits}f}" if abs(x) < 1e5 else f"{x:.4g}"


@dataclass(frozen=True)
class Analysis:
    """Result of :func:`analyze`; see ``to_json`` for the stable key names (SI units).

    Per-vehicle tuples are in team order; ``worst_vehicle`` is a vehicle id.
    """

    team: str
    vehicles: int
    gravity: float
    payload_share: int
    equilibrium_tension: float
    equilibrium_rope_angle: float
    vertical_load: float
    max_tilt: float
    bank_limit: float
    horizontal_force: float
    nominal_span: float
    rope_pull_nominal: float
    design_rope_angle: float
    design_span: float
    rope_pull_design: float
    rope_pull_bound: float
    rope_pull_bound_span: float
    worst_edge: float
    rope_pull_worst_edge: float
    max_accel: float
    max_accel_axis: float
    gain_terms: dict[str, float]
    gain_coefficients: dict[str, float]
    gain_lhs: float
    configured_accel_norm: float
    configured_accel_axis: float
    safe_span: float
    safe_deformation: float
    load: StaticShares
    largest_payload: float
    lift_altitude: float
    lift_ceiling: float
    scale_min_flown: float
    """The smallest scale the GCS flies (:func:`flown_scale_min`)."""
    scale_max_flown: float
    """The largest scale the GCS flies (:func:`flown_scale_max`)."""
    shape_hold: ShapeHold
    """The shape's weakest mode and the distance error it allows (:mod:`._shape_hold`)."""
    violations: tuple[Violation, ...] = field(default=())
    warnings: tuple[str, ...] = field(default=())

    @property
    def ok(self) -> bool:
        """True when no term is violated."""
        return not self.violations

    @property
    def unchecked_only(self) -> bool:
        """True when the one violation is the team's size, beyond the teams the analysis
        is checked on: ``--verify`` still flies it, and its flights are the certificate."""
        return bool(self.violations) and all(v.term == "vehicles" for v in self.violations)

    def to_json(self) -> dict[str, object]:
        """One JSON-ready object with stable keys (documented in docs/analysis.md)."""
        ld = self.load

        def nums(xs: tuple[float, ...]) -> list[float | None]:
            return [_num(x) for x in xs]

        return {
            "team": self.team,
            "vehicles": self.vehicles,
            "gravity_m_s2": _num(self.gravity),
            "payload_share": self.payload_share,
            "equilibrium_tension_N": _num(self.equilibrium_tension),
            "equilibrium_rope_angle_rad": _num(self.equilibrium_rope_angle),
            "vertical_load_N": _num(self.vertical_load),
            "max_tilt_rad": _num(self.max_tilt),
            "bank_limit_rad": _num(self.bank_limit),
            "horizontal_force_N": _num(self.horizontal_force),
            "rope_pull": {
                "nominal_span_m": _num(self.nominal_span),
                "nominal_N": _num(self.rope_pull_nominal),
                "design_rope_angle_rad": _num(self.design_rope_angle),
                "design_span_m": _num(self.design_span),
                "design_N": _num(self.rope_pull_design),
                "bound_N": _num(self.rope_pull_bound),
                "bound_span_m": _num(self.rope_pull_bound_span),
                "worst_edge_m": _num(self.worst_edge),
                "worst_edge_N": _num(self.rope_pull_worst_edge),
            },
            "max_guidance_accel_m_s2": _num(self.max_accel),
            "max_guidance_accel_axis_m_s2": _num(self.max_accel_axis),
            "gain_condition": {
                "terms_m_s2": {k: _num(v) for k, v in self.gain_terms.items()},
                "coefficients": {k: _num(v) for k, v in self.gain_coefficients.items()},
                "lhs_m_s2": _num(self.gain_lhs),
                "rhs_m_s2": _num(self.max_accel_axis),
                "ok": self.gain_lhs <= self.max_accel_axis,
            },
            "configured_limits": {
                "accel_norm_m_s2": _num(self.configured_accel_norm),
                "accel_axis_m_s2": _num(self.configured_accel_axis),
            },
            "safe_deformation": {
                "span_m": _num(self.safe_span),
                "margin_m": _num(self.safe_deformation),
            },
            "static_load": {
                "rope_lengths_m": nums(ld.rope_lengths),
                "taut": list(ld.taut),
                "tension_N": nums(ld.tension),
                "vertical_N": nums(ld.vertical),
                "horizontal_N": nums(ld.horizontal),
                "share": nums(ld.share),
                "payload_offset_m": nums(ld.payload_offset),
                "hang_depth_m": _num(ld.hang_depth),
                "statically_determinate": ld.determinate,
                "assumed_share": _num(ld.assumed_share),
                "worst_share": _num(ld.worst_share),
                "worst_vehicle": ld.worst_vehicle,
                "position_error_m": _num(ld.position_error),
                "hold_stiffness_N_m": _num(ld.hold_stiffness),
                "worst_tension_N": _num(ld.worst_tension),
                "worst_horizontal_N": _num(ld.worst_horizontal),
                "worst_vertical_load_N": _num(ld.worst_vertical_load),
                "design_share": _num(ld.design_share),
                "design_basis": ld.design_basis or None,
                "even_rope_lengths_m": (None if ld.even_rope_lengths is None
                                        else nums(ld.even_rope_lengths)),
                "accel_m_s2": _num(ld.accel),
                "accel_share": _num(ld.accel_share),
                "accel_vehicle": ld.accel_vehicle,
                "accel_tension_N": _num(ld.accel_tension),
            },
            "largest_payload_kg": _num(self.largest_payload),
            "lift": {"altitude_m": _num(self.lift_altitude),
                     "ceiling_m": _num(self.lift_ceiling)},
            "scales_flown": {"min": _num(self.scale_min_flown),
                             "max": _num(self.scale_max_flown)},
            "shape_hold": {
                "weakest_stiffness": _num(self.shape_hold.stiffness),
                "disturbance_m_s2": _num(self.shape_hold.disturbance),
                "drift_error_m": _num(self.shape_hold.drift_error),
                "new_edges": [list(e) for e in self.shape_hold.new_edges],
                "new_stiffness": _num(self.shape_hold.new_stiffness),
            },
            "violations": [asdict(v) for v in self.violations],
            "warnings": list(self.warnings),
            "ok": self.ok,
        }


def _num(x: float) -> float | None:
    return None if not math.isfinite(x) else round(float(x), 6) + 0.0


@dataclass(frozen=True)
class StaticShares:
    """The payload's load on each vehicle from the team's geometry (team order).

    ``tension`` .. ``share`` are at the desired shape (stiff ropes); ``worst_*`` over the
    vehicles anywhere within ``position_error`` of their places, on ropes that give by
    ``hold_stiffness``; ``design_share`` is what the force chain (eq. T, Th, the vertical
    load) designs for: the larger of the assumed share and the share at rest; ``accel_*``
    with the payload accelerating at the guidance's limit (the shapes of ``worst_*``).
    """

    rope_lengths: tuple[float, ...]
    taut: tuple[bool, ...]
    tension: tuple[float, ...]
    vertical: tuple[float, ...]
    horizontal: tuple[float, ...]
    share: tuple[float, ...]
    payload_offset: tuple[float, float]
    hang_depth: float
    determinate: bool
    assumed_share: float
    worst_share: float
    worst_vehicle: int
    position_error: float
    hold_stiffness: float
    worst_tension: float
    worst_horizontal: float
    worst_vertical_load: float
    design_share: float
    even_rope_lengths: tuple[float, ...] | None
    design_basis: str = ""
    """Why the design share is the worst share (empty: the larger of the assumed share and
    the share at rest, which load sharing holds)."""
    accel: float = math.nan
    """The payload's horizontal acceleration of the ``accel_*`` figures (limits.accel_norm)."""
    accel_share: float = math.nan
    """The largest share on one vehicle with the payload accelerating at ``accel`` in any
    horizontal direction, at the desired shape and at the largest scale flown
    (:func:`accelerating_share`; a shape shrunk below 1 loads one vehicle more)."""
    accel_vehicle: int = 0
    accel_tension: float = math.nan
    """The largest rope tension then, N."""


def _kappa(team: Team) -> float:
    """Largest sum of |unit edge vector . axis| over one vehicle's edges, team axes."""
    f = team.formation
    q = f.positions[:, None, :] - f.positions[f.slot_neighbour]
    qhat = q / np.maximum(np.linalg.norm(q, axis=2, keepdims=True), 1e-12)
    return float((np.abs(qhat) * f.slot_mask[..., None]).sum(axis=1).max())


def _motion_warnings(unavailable: tuple[str, ...], mu_r: float) -> list[str]:
    """What the sticks cannot do for a team whose vehicles have one edge each (a pair)."""
    out = []
    sticks = [stick for motion, stick in (("translate_x", "forward"), ("translate_y", "right"))
              if motion in unavailable]
    if sticks:
        out.append(f"each vehicle has one edge, so the team moves along it only, never "
                   f"sideways to it: the {' and '.join(sticks)} stick"
                   f"{'s do' if len(sticks) > 1 else ' does'} nothing")
    if "rotate" in unavailable and mu_r > 0:
        out.append(f"the team cannot spin (each vehicle has one edge): "
                   f"guidance.max_rotation_disagreement {mu_r:g} has no effect")
    return out


@dataclass(frozen=True)
class _Chain:
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


def _chain(team: Team, mass: float, share: float) -> _Chain:
    """Eq. T / Th's chain: vertical load, largest tilt, horizontal force, rope pull at the
    design angle, largest acceleration and the safe span, for ``mass`` kg carried at
    ``share`` of its weight per vehicle."""
    cfg = team.config
    g, m = cfg.analysis.gravity, cfg.airframe.mass
    load = (m + mass * share) * g
    thrust_ref = cfg.airframe.thrust_reference
    max_tilt = math.acos(load / thrust_ref) if load < thrust_ref else 0.0
    f_h = thrust_ref * math.sin(cfg.limits.bank)
    weight_share = mass * g * share
    theta = math.radians(cfg.analysis.design_rope_angle_deg)
    rope = min(cfg.payload.lengths(team.formation.n))
    t_design = rope_pull(weight_share, rope, 2.0 * rope * math.sin(theta))
    max_accel = (f_h - t_design) / m
    safe_span = a_safe_span(f_h, m, cfg.limits.accel_norm, weight_share, rope)
    return _Chain(load=load, max_tilt=max_tilt, horizontal_force=f_h, weight_share=weight_share,
                  rope_pull_design=t_design, max_accel=max_accel,
                  max_axis=max_accel * _AXIS_FACTOR, safe_span=safe_span,
                  safe_margin=safe_span - 2.0 * float(team.formation.radii.max()))


def flown_scale_max(team: Team, safe_span: float) -> float:
    """The largest scale the GCS flies: ``guidance.scale_max`` capped inside the safe span
    (4 % short of it, never below 1): 2 % for the distance errors and the payload's swing,
    2 % for the overshoot of a growing shape, which the distance term alone brings to the
    new scale (the square overshot by 3 % of its radius at ``operator.scale_rate`` 0.1/s
    and flew 2 cm beyond the safe span with the cap at 2 %)."""
    guidance = team.config.guidance
    radius = float(team.formation.radii.max())
    safe = 0.5 * safe_span / radius if radius > 0 else math.inf
    return guidance.scale_max if safe >= guidance.scale_max else max(1.0, 0.96 * safe)


class SmallestScale(NamedTuple):
    """The smallest scale flown, and why not smaller."""

    scale: float
    share_at_scale_min: float
    """The accelerating share at ``guidance.scale_min`` (inf: the ropes cannot hang it)."""


def flown_scale_min(team: Team) -> SmallestScale:
    """The smallest scale the GCS flies: ``guidance.scale_min`` raised (never above 1) until
    the payload, accelerating at ``limits.accel_norm``, loads no vehicle up to the reference
    thrust (85 % of its capacity).

    A shrunk shape hangs the payload from steeper ropes, which let it swing towards the
    side it accelerates to: the paper's square at half size puts 0.667 of the payload on
    one vehicle at its acceleration limit (0.386 at scale 1), and at 0.3 all of it, beyond
    the Bebop's full thrust. The share falls as the scale grows (bisection, to 0.005).
    """
    cfg = team.config
    mass, load_max = cfg.airframe.mass, cfg.airframe.thrust_reference
    g, payload, accel = cfg.analysis.gravity, cfg.payload.mass, cfg.limits.accel_norm

    def share(scale: float, directions: np.ndarray | None = None) -> float:
        try:
            return accelerating_share(team, accel, (scale,), directions).share
        except NoHangingPointError:
            return math.inf

    def flown(scale: float, directions: np.ndarray | None = None) -> bool:
        return (mass + payload * share(scale, directions)) * g < load_max

    low = cfg.guidance.scale_min
    at_min = share(low)
    if (mass + payload * at_min) * g < load_max:
        return SmallestScale(low, at_min)
    try:  # the worst direction barely turns with the scale: search near it, then check all
        worst = accelerating_share(team, accel).direction
    except NoHangingPointError:
        return SmallestScale(1.0, at_min)
    near = worst + np.radians(np.arange(-10.0, 10.5, 5.0))
    high = 1.0
    if not flown(high, near):
        return SmallestScale(1.0, at_min)  # the share at scale 1 is the accelerating warning
    while high - low > 0.005:
        mid = 0.5 * (low + high)
        low, high = (low, mid) if flown(mid, near) else (mid, high)
    smallest = math.ceil(high * 1000.0) / 1000.0
    while smallest < 1.0 and not flown(smallest):  # another direction is worse there
        smallest = min(1.0, smallest + 0.005)
    return SmallestScale(smallest, at_min)


def _scale_min_warning(team: Team, smallest: SmallestScale) -> str:
    """``guidance.scale_min`` raised in flight: why, and what flies the configured one."""
    cfg = team.config
    low = cfg.guidance.scale_min
    share = smallest.share_at_scale_min
    load = (cfg.airframe.mass + cfg.payload.mass * share) * cfg.analysis.gravity
    what = (f"accelerating at limits.accel_norm {cfg.limits.accel_norm:g} m/s^2 puts "
            f"{share:.3f} of the payload on one vehicle: a vertical load of {_n(load, 2)} N "
            f"not below the reference thrust {_n(cfg.airframe.thrust_reference, 2)} N (85 % "
            f"of full thrust)" if math.isfinite(share) else "the ropes cannot hang the payload")
    return (f"the GCS flies scales from {smallest.scale:g}, not guidance.scale_min {low:g}: "
            f"at {low:g}, {what}; guidance.scale_min at least {smallest.scale:g} says so in "
            f"the config")


def _worst_flown_load(team: Team, scales: tuple[float, ...]) -> WorstLoad:
    """The worst load within ``analysis.position_error`` over the shapes of ``scales``: the
    largest share, tension and pull of them."""
    cfg = team.config.analysis
    worst = [worst_load(team, cfg.position_error, stiffness=cfg.hold_stiffness, scale=s)
             for s in scales]
    top = max(worst, key=lambda w: w.share)
    return dataclasses.replace(top, tension=max(w.tension for w in worst),
                               horizontal=max(w.horizontal for w in worst),
                               tried=sum(w.tried for w in worst))


def _carries(team: Team, mass: float, share: float, gain_lhs: float, worst_share: float) -> bool:
    """Whether every payload-bound condition holds for ``mass`` kg at ``share`` (and at
    ``worst_share``, the full-speed thrust)."""
    cfg = team.config
    c = _chain(team, mass, share)
    worst = (cfg.airframe.mass + mass * worst_share) * cfg.analysis.gravity
    return (c.load < cfg.airframe.thrust_reference and worst < cfg.airframe.thrust_max
            and cfg.limits.bank < c.max_tilt and c.max_accel > 0.0
            and cfg.limits.accel_norm <= c.max_accel and cfg.limits.accel_axis <= c.max_axis
            and gain_lhs <= c.max_axis and c.safe_margin > 0.0)


def largest_payload(team: Team, share: float, gain_lhs: float, worst_share: float) -> float:
    """The heaviest payload, kg, for which every payload-bound condition holds with each
    vehicle carrying ``share`` of it, and ``worst_share`` within full thrust (bisection; 0
    when even a feather fails). The shares are the geometry's: they do not depend on the
    mass."""
    if not _carries(team, 1e-9, share, gain_lhs, worst_share):
        return 0.0
    cfg = team.config
    lo, hi = 0.0, cfg.airframe.thrust_max / cfg.analysis.gravity / share
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _carries(team, mid, share, gain_lhs, worst_share) else (lo, mid)
    return lo


def _shares(team: Team, assumed: float) -> tuple[StaticShares | None, str | None]:
    """The static load at the desired shape (None and why when the ropes cannot hang it)."""
    cfg = team.config
    lengths = cfg.payload.lengths(team.formation.n)
    try:
        at_rest = desired_load(team)
    except ValueError as exc:
        return None, str(exc)
    taut = tuple(bool(t) for t in at_rest.taut)
    offset = (float(at_rest.payload_ned[0]), float(at_rest.payload_ned[1]))
    even = None
    if not all(taut) or math.hypot(*offset) > 1e-3 * min(lengths):
        even = tuple(float(x) for x in even_rope_lengths(team))
    share = float(at_rest.share.max())
    return StaticShares(
        rope_lengths=tuple(lengths), taut=taut,
        tension=tuple(float(x) for x in at_rest.tension),
        vertical=tuple(float(x) for x in at_rest.vertical),
        horizontal=tuple(float(x) for x in at_rest.horizontal),
        share=tuple(float(x) for x in at_rest.share), payload_offset=offset,
        hang_depth=float(at_rest.payload_ned[2]), determinate=sum(taut) <= 3,
        assumed_share=assumed, worst_share=share,
        worst_vehicle=team.formation.ids[int(np.argmax(at_rest.share))],
        position_error=0.0, hold_stiffness=cfg.analysis.hold_stiffness,
        worst_tension=float(at_rest.tension.max()),
        worst_horizontal=float(at_rest.horizontal.max()),
        worst_vertical_load=(cfg.airframe.mass + cfg.payload.mass * share) * cfg.analysis.gravity,
        design_share=max(assumed, share), even_rope_lengths=even), None


def _ids(team: Team, mask: tuple[bool, ...]) -> str:
    return ", ".join(str(i) for i, on in zip(team.formation.ids, mask, strict=True) if on)


def _lengths_text(lengths: tuple[float, ...], configured: tuple[float, ...]) -> str:
    """``lengths`` to the mm, or finer where that would print a length that differs from
    its configured one as the same (positions rounded to a tenth of a mm leave a ring's
    ropes micrometres from taut)."""
    digits = 3
    while digits < 6 and any(abs(a - b) > 0.5e-6 and f"{a:.{digits}f}" == f"{b:.{digits}f}"
                             for a, b in zip(lengths, configured, strict=True)):
        digits += 1
    return ", ".join(f"{x:.{digits}f}" for x in lengths)


def _load_warnings(team: Team, ld: StaticShares, scales: tuple[float, ...]) -> list[str]:
    """What the geometry says that the paper's fixed share does not (``scales``: those
    flown)."""
    out = []
    ids = team.formation.ids
    if ld.even_rope_lengths is not None:
        slack = tuple(not t for t in ld.taut)
        carry = ", ".join(f"{i} {s:.3f}" for i, s, t in zip(ids, ld.share, ld.taut, strict=True)
                          if t)
        lengths = _lengths_text(ld.even_rope_lengths, ld.rope_lengths)
        head = (f"at the desired shape the ropes of vehicles {_ids(team, slack)} are slack"
                if any(slack) else "at the desired shape the payload hangs "
                f"{math.hypot(*ld.payload_offset):.3f} m off the centroid")
        out.append(f"{head}: shares of the payload {carry}; ropes of [{lengths}] m "
                   f"(payload.rope_lengths, in the order of vehicles) hang it under the "
                   f"centroid with every rope taut")
    if ld.worst_share > ld.design_share + 1e-3:
        need = max(1, math.floor(1.0 / ld.worst_share + 1e-9))
        cfg = team.config
        chain = _chain(team, cfg.payload.mass, ld.worst_share)
        left = (f"{_n(chain.max_accel)} m/s^2 of guidance acceleration left"
                if chain.max_accel > 0.0 else "no guidance acceleration left")
        over = (f", above the reference thrust {_n(cfg.airframe.thrust_reference, 2)} N"
                if ld.worst_vertical_load >= cfg.airframe.thrust_reference else "")
        out.append(f"with the vehicles up to {ld.position_error:g} m off their places "
                   f"(analysis.position_error) vehicle {ld.worst_vehicle} can carry "
                   f"{ld.worst_share:.3f} of the payload ({sum(ld.taut)} taut ropes"
                   f"{' share it statically indeterminately' if not ld.determinate else ''}), "
                   f"where the analysis designs for {ld.design_share:.3f}: a vertical load of "
                   f"{_n(ld.worst_vertical_load, 2)} N{over}, {left}; "
                   f"analysis.payload_share: {need} designs for it")
    if ld.accel_share > ld.design_share + 1e-3:
        out.append(_accel_warning(team, ld, scales))
    if ld.design_basis:
        out.append(f"{ld.design_basis}: the analysis designs for the worst share "
                   f"{ld.worst_share:.3f}")
    return out


def _split_unheld(team: Team, ld: StaticShares) -> str | None:
    """Why nothing keeps the payload's split at the design share, or None when load
    sharing does (or three ropes or fewer fix it). Four or more taut ropes split it by
    fractions of a millimetre of the shape: without load sharing the paper's square flew
    one vehicle at 0.37 of it. Load sharing is checked in the simulator to hold teams of
    up to :data:`SHARED_ROPES_CHECKED` taut ropes within their design share (the
    hexagon's six at 0.251 of the payload); on twelve (a ring of twelve, eight ropes taut
    at rest) one vehicle flew 0.29 of it against a design 0.193, and with the shape bent
    0.7 m ropes went slack and one carried 0.72."""
    taut = sum(ld.taut)
    if ld.determinate:
        return None
    if not team.config.flight.load_sharing:
        return (f"flight.load_sharing is off: {taut} taut ropes split the payload by "
                f"fractions of a millimetre of the shape (the paper's square flew one "
                f"vehicle at 0.37 of it)")
    if taut > SHARED_ROPES_CHECKED:
        return (f"load sharing is checked to hold the design share on up to "
                f"{SHARED_ROPES_CHECKED} taut ropes, and this team hangs the payload from "
                f"{taut} (a ring of twelve flew one vehicle at 0.29 of it against a design "
                f"0.193)")
    return None


def _accel_keeping_share(team: Team, share: float, accel: float, guess: float,
                         scales: tuple[float, ...] = (1.0,)) -> float:
    """The largest acceleration below ``accel`` that loads no vehicle beyond ``share`` at
    any of ``scales``, to 1/1000 of ``accel``, searched from ``guess`` (the share's linear
    estimate); 0 where even a tenth of ``accel`` does (then no limit is worth naming)."""
    def keeps(a: float) -> bool:  # the smallest scale loads one vehicle most
        return accelerating_share(team, a, (min(scales),)).share <= share

    if guess <= 0.0:  # already beyond the share at rest
        return 0.0
    if keeps(guess):
        low, high = guess, accel  # ``accel`` itself loads one vehicle beyond it
    else:
        low, high = 0.1 * accel, guess
        if not keeps(low):
            return 0.0
    while high - low > 1e-3 * accel:  # bisection: the share grows with the acceleration
        mid = 0.5 * (low + high)
        low, high = (mid, high) if keeps(mid) else (low, mid)
    return low


def _accel_warning(team: Team, ld: StaticShares, scales: tuple[float, ...]) -> str:
    """The payload accelerating at the guidance's limit loads a vehicle beyond the design
    share: by how much, and the acceleration limit that keeps it within."""
    cfg = team.config
    rest = max(ld.share)
    fix = _accel_keeping_share(team, ld.design_share, ld.accel,
                               ld.accel * (ld.design_share - rest) / max(ld.accel_share - rest,
                                                                         1e-12), scales)
    load = (cfg.airframe.mass + cfg.payload.mass * ld.accel_share) * cfg.analysis.gravity
    over = (f", above the reference thrust {_n(cfg.airframe.thrust_reference, 2)} N"
            if load >= cfg.airframe.thrust_reference else "")
    axis = (f" (and limits.accel_axis, now {cfg.limits.accel_axis:g})"
            if cfg.limits.accel_axis > fix else "")
    named = (f"limits.accel_norm at most {_floor3(fix)}{axis} keeps it within the design share"
             if fix >= 0.1 * ld.accel else
             f"analysis.payload_share: {max(1, math.floor(1.0 / ld.accel_share + 1e-9))} "
             f"designs for it (any acceleration loads it beyond the share at rest)")
    chain = _chain(team, cfg.payload.mass, ld.accel_share)
    left = (f"{_n(chain.max_accel)} m/s^2 of guidance acceleration left"
            if chain.max_accel > 0.0 else "no guidance acceleration left")
    return (f"with the payload accelerating at limits.accel_norm {ld.accel:g} m/s^2 vehicle "
            f"{ld.accel_vehicle} carries {ld.accel_share:.3f} of it, "
            f"where the analysis designs for {ld.design_share:.3f}: a vertical load of "
            f"{_n(load, 2)} N{over}, {left}; {named}")


CHECKED_TEAM_SIZE = 6
"""The largest team the analysis is checked on against the simulator (the hexagon). On
rings of twelve that it passed, the weakest mode's bound held neither the distance error
(1.0 to 2.1 m flown against 0.65 m bound, 0.79 m safe) nor load sharing the split
(docs/analysis.md): beyond it, ``gcs analyze --verify`` is the certificate."""

SHARED_ROPES_CHECKED = 6
"""The most taut ropes on which load sharing is checked in the simulator to hold the
payload's split within the design share (the hexagon)."""

_ANALYSES: collections.OrderedDict[TeamConfig, Analysis] = collections.OrderedDict()
_ANALYSES_KEPT = 32
"""Analyses kept by config value: a process that loads the same file again (a test
suite's worker, flights of many seeds) asks for the same analysis."""
_ANALYSES_LOCK = threading.Lock()


def analyze(team: Team) -> Analysis:
    """Run the worst-case analysis of a loaded team.

    Once per team (0.3 s for the square): a loaded team is frozen, its analysis a
    function of its config alone, and the command line, the scenario check and the GCS
    each ask for the same team's."""
    with _ANALYSES_LOCK:
        known = _ANALYSES.get(team.config)
    if known is None:
        known = _analyze(team)
    with _ANALYSES_LOCK:
        _ANALYSES[team.config] = known
        _ANALYSES.move_to_end(team.config)
        while len(_ANALYSES) > _ANALYSES_KEPT:
            _ANALYSES.popitem(last=False)
    return known


def _with_payload(team: Team, mass: float) -> Team:
    payload = dataclasses.replace(team.config.payload, mass=mass)
    return dataclasses.replace(team, config=dataclasses.replace(team.config, payload=payload))


def _settled_payload(team: Team, mass: float) -> float:
    """``mass`` (a lighter payload :func:`largest_payload` found at this team's scales)
    lowered until the team carrying it breaks no payload-bound condition: a lighter payload
    flies smaller scales (the accelerating share allows them), whose steeper ropes load one
    vehicle more; without load sharing the paper's square was named 0.257 kg, which then
    failed eq. max, and 0.187 kg holds."""
    for _ in range(8):
        if mass <= 0.0:
            return 0.0
        again = _analyze(_with_payload(team, mass), settle=False)
        if again.largest_payload >= mass * (1.0 - 1e-6):  # it carries itself at its scales
            return mass
        mass = min(again.largest_payload, 0.99 * mass)
    return mass


def _analyze(team: Team, *, settle: bool = True) -> Analysis:
    cfg = team.config
    f = team.formation
    g = cfg.analysis.gravity
    n = f.n
    m = cfg.airframe.mass
    M = cfg.payload.mass
    lengths = cfg.payload.lengths(n)
    l = min(lengths)
    share_div = cfg.analysis.payload_share or max(n - 1, 1)
    assumed = 1.0 / share_div
    violations: list[Violation] = []
    warnings: list[str] = []

    r_nom = float(f.radii.max())
    ld, unreachable = _shares(team, assumed)
    if ld is None:
        violations.append(Violation("payload.rope_length", f"the ropes cannot hang the "
                                    f"payload: {unreachable}"))
        tension = eq_angle = math.inf
        design = assumed
    else:
        tension = max(ld.tension)
        eq_angle = max(math.atan2(h, v) for h, v, t in
                       zip(ld.horizontal, ld.vertical, ld.taut, strict=True) if t)
        design = ld.design_share

    e_max = cfg.analysis.max_distance_error
    ev_max = cfg.analysis.max_speed_error or cfg.guidance.max_speed
    basis = motion_basis(f)
    warnings += _motion_warnings(basis.unavailable, cfg.guidance.max_rotation_disagreement)
    rot_edges = np.abs(basis.rotate).max(axis=0) > 1e-9
    worst_edge = float(f.distances[rot_edges].max() if rot_edges.any() else f.distances.max())
    worst_edge += e_max
    kappa = _kappa(team)
    mu_r = cfg.guidance.max_rotation_disagreement
    terms = {
        "c1_speed": cfg.guidance.c1 * ev_max,
        "c2_distance": cfg.guidance.c2 * e_max * kappa,
        "mu_rotation": mu_r * worst_edge,
    }
    lhs = sum(terms.values())

    chain = _chain(team, M, design)
    smallest, largest = cfg.guidance.scale_min, flown_scale_max(team, chain.safe_span)
    if ld is not None:
        floor = flown_scale_min(team)
        smallest = floor.scale
        if smallest > cfg.guidance.scale_min:
            warnings.append(_scale_min_warning(team, floor))
        # the smallest scale flown (steepest ropes), the desired shape, the largest (they
        # lean most): their loads bound every shape flown with the payload
        flown = tuple(sorted({smallest, 1.0, largest}))
        worst = _worst_flown_load(team, flown)
        accelerating = accelerating_share(team, cfg.limits.accel_norm, flown)
        ld = dataclasses.replace(  # the accel limit named in a warning keeps every scale flown
            ld, worst_share=worst.share, worst_vehicle=f.ids[worst.vehicle],
            position_error=worst.error, worst_tension=worst.tension,
            worst_horizontal=worst.horizontal,
            worst_vertical_load=(m + M * worst.share) * g,
            accel=accelerating.accel, accel_share=accelerating.share,
            accel_vehicle=f.ids[accelerating.vehicle], accel_tension=accelerating.tension)
        unheld = _split_unheld(team, ld)
        if unheld is not None and ld.worst_share > design:
            # nothing is known to keep the split at the design share: design for the worst
            design = ld.worst_share
            ld = dataclasses.replace(ld, design_share=design, design_basis=unheld)
            chain = _chain(team, M, design)
            largest = min(largest, flown_scale_max(team, chain.safe_span))
        warnings += _load_warnings(team, ld, flown)
    worst_share = ld.worst_share if ld is not None else design
    heaviest = largest_payload(team, design, lhs, worst_share)
    if settle and 0.0 < heaviest < M:
        heaviest = _settled_payload(team, heaviest)
    lighter = {"payload.mass": heaviest} if 0.0 < heaviest < M else {}
    lighter_text = f"; or carry at most {_floor3(heaviest)} kg (payload.mass)" if lighter else ""
    only_lighter = f"; carry at most {_floor3(heaviest)} kg (payload.mass)" if lighter else ""

    load, max_tilt, f_h = chain.load, chain.max_tilt, chain.horizontal_force
    thrust_ref = cfg.airframe.thrust_reference
    share_text = f"{design:.3f} of the payload"
    if load >= thrust_ref:
        violations.append(Violation("airframe.thrust_reference",
                                    f"vertical load {_n(load, 2)} N ({share_text}) is not below "
                                    f"the reference thrust {_n(thrust_ref, 2)} N: the vehicle "
                                    f"cannot carry its share{only_lighter}", lighter))
    thrust_max = cfg.airframe.thrust_max
    worst_load_ = (m + M * worst_share) * g
    if load < thrust_max <= worst_load_:
        violations.append(Violation("airframe.thrust_max",
                                    f"with the vehicles up to {cfg.analysis.position_error:g} m "
                                    f"off their places, the vertical load {_n(worst_load_, 2)} N "
                                    f"({worst_share:.3f} of the payload) is not below the "
                                    f"full-speed thrust {thrust_max:.3g} N: the vehicle cannot "
                                    f"hold its worst share{only_lighter}", lighter))
    if load >= thrust_max:
        violations.append(Violation("airframe.thrust_max",
                                    f"vertical load {_n(load, 2)} N is not below the full-speed "
                                    f"thrust {thrust_max:.3g} N (4 x thrust_coefficient x "
                                    f"rotor_speed_max^2): the vehicle cannot lift itself and "
                                    f"its share of the payload{only_lighter}", lighter))
    bank = cfg.limits.bank
    if 0.0 < max_tilt <= bank:
        tilt_deg = math.degrees(max_tilt)
        violations.append(Violation("limits.bank_deg",
                                    f"bank limit {_n(bank)} rad is not below the largest tilt "
                                    f"{_n(max_tilt)} rad that still carries {_n(load, 2)} N: set "
                                    f"it below {_floor3(tilt_deg)} degrees{lighter_text}",
                                    {"limits.bank_deg": tilt_deg, **lighter}))

    weight_share = chain.weight_share
    theta = math.radians(cfg.analysis.design_rope_angle_deg)
    design_span = 2.0 * l * math.sin(theta)
    t_design = chain.rope_pull_design
    if theta < eq_angle:
        warnings.append(f"the design rope angle {_n(theta)} rad is below the rope angle of the "
                        f"nominal shape {_n(eq_angle)} rad")
    max_accel, max_axis = chain.max_accel, chain.max_axis
    if max_accel <= 0:
        violations.append(Violation("analysis.design_rope_angle_deg",
                                    f"the rope pull {_n(t_design, 2)} N at the design angle "
                                    f"exceeds the horizontal force {_n(f_h, 2)} N left at the "
                                    f"bank limit{only_lighter}", lighter))
    if lhs > max_axis > 0.0:  # none left at all: the limits' violations say so
        violations.append(gain_violation(terms, {"c1_speed": ev_max,
                                                 "c2_distance": e_max * kappa,
                                                 "mu_rotation": worst_edge}, max_axis))
    if cfg.limits.accel_norm > max_accel:
        violations.append(_limit_violation("limits.accel_norm", cfg.limits.accel_norm,
                                           "the largest guidance acceleration", max_accel,
                                           lighter, heaviest))
    if cfg.limits.accel_axis > max_axis:
        violations.append(_limit_violation("limits.accel_axis", cfg.limits.accel_axis,
                                           "the per-axis limit", max_axis, lighter,
                                           heaviest))

    # Largest vehicle-payload distance that leaves the configured acceleration available.
    safe_span, safe_margin = chain.safe_span, chain.safe_margin
    if safe_margin <= 0 and not violations:
        left = (f_h - rope_pull(weight_share, l, 2 * r_nom)) / m
        fixes = {"limits.accel_norm": left, **lighter} if left > 0 else dict(lighter)
        named = [f"limits.accel_norm at most {_floor3(left)}"] if left > 0 else []
        named += [f"payload.mass at most {_floor3(heaviest)} kg"] if lighter else []
        violations.append(Violation("limits.accel_norm",
                                    "the nominal shape already pulls the ropes too hard "
                                    "to leave the configured acceleration"
                                    + (f": set {' or '.join(named)}" if named else ""), fixes))
    if e_max > safe_margin > 0:
        warnings.append(f"eq. max assumes distance errors up to {_n(e_max, 2)} m, beyond the "
                        f"safe deformation of {_n(safe_margin)} m")

    hold = shape_hold(f, cfg.guidance.c2, cfg.analysis.disturbance_accel, safe_margin)
    if safe_margin > 0 and hold.drift_error > safe_margin:
        # the distance gain eq. max leaves room for, the other terms as they are
        c2_room = (max_axis - lhs + terms["c2_distance"]) / (e_max * kappa)
        violations.append(_hold_violation(team, hold, safe_margin, c2_room))

    if n > CHECKED_TEAM_SIZE:
        violations.insert(0, _size_violation(n))
    lift_altitude, ceiling = _lift(team, violations)

    return Analysis(
        team=cfg.name, vehicles=n, gravity=g, payload_share=share_div,
        equilibrium_tension=tension, equilibrium_rope_angle=eq_angle,
        vertical_load=load, max_tilt=max_tilt, bank_limit=bank, horizontal_force=f_h,
        nominal_span=2 * r_nom, rope_pull_nominal=rope_pull(weight_share, l, 2 * r_nom),
        design_rope_angle=theta, design_span=design_span, rope_pull_design=t_design,
        rope_pull_bound=weight_share, rope_pull_bound_span=l * math.sqrt(2.0),
        worst_edge=worst_edge, rope_pull_worst_edge=rope_pull(weight_share, l, worst_edge),
        max_accel=max_accel, max_accel_axis=max_axis, gain_terms=terms,
        gain_coefficients={"c1": cfg.guidance.c1, "c2": cfg.guidance.c2,
                           "mu_r": mu_r, "speed_error_m_s": ev_max,
                           "distance_error_m": e_max, "kappa": kappa,
                           "worst_edge_m": worst_edge},
        gain_lhs=lhs, configured_accel_norm=cfg.limits.accel_norm,
        configured_accel_axis=cfg.limits.accel_axis,
        safe_span=safe_span, safe_deformation=safe_margin,
        load=ld if ld is not None else _no_shares(lengths, assumed),
        largest_payload=heaviest, lift_altitude=lift_altitude, lift_ceiling=ceiling,
        scale_min_flown=smallest, scale_max_flown=largest, shape_hold=hold,
        violations=tuple(violations), warnings=tuple(warnings),
    )


def _size_violation(n: int) -> Violation:
    """A team larger than those the analysis is checked on: refused, with how to certify
    it by flying it."""
    return Violation(
        "vehicles",
        f"a team of {n} is beyond the {CHECKED_TEAM_SIZE} vehicles the analysis is checked on "
        f"in the simulator (a ring of twelve it passed flew 2.1 m of distance error against "
        f"0.79 m safe): `gcs analyze --verify` flies it, and --override-analysis flies it "
        f"once that passes")


def _hold_violation(team: Team, hold: ShapeHold, safe: float, c2_room: float) -> Violation:
    """The shape's weakest mode lets the unseen disturbance bend it past the safe
    deformation: the distance gain that holds it (and whether eq. max leaves room for
    it, ``c2_room``), and the edges that stiffen it."""
    c2 = team.config.guidance.c2
    needed = c2 * hold.drift_error / safe
    gain = (f"raise guidance.c2 to at least {needed:.3f}" if needed <= c2_room else
            f"guidance.c2 would need at least {needed:.3f}, beyond the {max(c2_room, 0.0):.3f} "
            f"eq. max leaves room for")
    tie = ", ".join(f"{i}-{j}" for i, j in hold.new_edges)
    edges = (f"tie vehicles {tie} (stiffness {hold.new_stiffness:.3g}; eq. max must "
             f"still hold with the longer edges)" if tie else "add edges across the shape")
    return Violation(
        "guidance.c2" if needed <= c2_room else "edges",
        f"the shape's weakest deformation mode (stiffness {hold.stiffness:.3g}; the "
        f"square's is 2) holds the distance errors only within {_n(hold.drift_error)} m "
        f"under an unseen {hold.disturbance:g} m/s^2 per vehicle "
        f"(analysis.disturbance_accel), beyond the safe deformation {_n(safe)} m: "
        + (f"{gain}, or {edges}" if needed <= c2_room else f"{edges} ({gain})"),
        {"guidance.c2": needed} if needed <= c2_room else {})


def _limit_violation(name: str, value: float, what: str, largest: float,
                     lighter: dict[str, float], heaviest: float) -> Violation:
    """A configured acceleration limit above what is left: the limit to set, when some is
    left, and the lighter payload (never a negative limit)."""
    mass = f"carry at most {_floor3(heaviest)} kg (payload.mass)"
    if largest > 0.0:
        return Violation(name, f"{value:g} m/s^2 exceeds {what} {_n(largest)} m/s^2: set it to "
                               f"at most {_floor3(largest)}" + (f"; or {mass}" if lighter else ""),
                         {name: largest, **lighter})
    return Violation(name, f"{value:g} m/s^2 exceeds {what} {_n(largest)} m/s^2: the rope pull "
                           f"leaves no acceleration at the bank limit"
                           + (f"; {mass}" if lighter else ""), lighter)


def _lift(team: Team, violations: list[Violation]) -> tuple[float, float]:
    """The altitude the lift climbs to (where the payload leaves the ground, at the smallest
    scale, plus the lift height) and the ceiling it must stay under; a violation when it
    does not."""
    cfg = team.config
    ceiling = min(cfg.operator.altitude_max, cfg.safety.geofence_altitude)
    try:
        depth = hang_depth(team, scale=cfg.guidance.scale_min)
    except ValueError:
        return math.inf, ceiling
    top = depth + cfg.flight.lift_height
    if top > ceiling:
        fixes = {"flight.lift_height": ceiling - depth} if ceiling > depth else {}
        lower = (f"set flight.lift_height at most {_floor3(ceiling - depth)}, or "
                 if fixes else "")
        violations.append(Violation(
            "flight.lift_height",
            f"the payload leaves the ground with the vehicles at {_n(depth)} m (at "
            f"guidance.scale_min {cfg.guidance.scale_min:g}), so lifting it "
            f"{cfg.flight.lift_height:g} m climbs to {_n(top)} m, above the ceiling "
            f"{_n(ceiling)} m (operator.altitude_max, safety.geofence_altitude): {lower}raise "
            f"both to at least {_n(top)}, or shorten the ropes by {_n(top - ceiling)} m",
            fixes))
    return top, ceiling


def _no_shares(lengths: tuple[float, ...], assumed: float) -> StaticShares:
    """The static load of ropes that cannot hang the payload: nothing known."""
    n = len(lengths)
    nan = (math.nan,) * n
    return StaticShares(rope_lengths=lengths, taut=(False,) * n, tension=nan, vertical=nan,
                        horizontal=nan, share=nan, payload_offset=(math.nan, math.nan),
                        hang_depth=math.nan, determinate=False, assumed_share=assumed,
                        worst_share=math.nan, worst_vehicle=0, position_error=math.nan,
                        hold_stiffness=math.nan, worst_tension=math.nan,
                        worst_horizontal=math.nan, worst_vertical_load=math.nan,
                        design_share=assumed, even_rope_lengths=None)


def format_report(a: Analysis, source: str) -> str:
    """Human-readable table of the analysis."""

    def val(x: float, unit: str, digits: int = 3) -> str:
        return "unreachable" if not math.isfinite(x) else f"{_n(x, digits)} {unit}"

    ld = a.load

    def each(xs: tuple[float, ...], digits: int = 3) -> str:
        return " ".join("-" if not math.isfinite(x) else f"{round(x, digits) + 0.0:.{digits}f}"
                        for x in xs)

    assumed = ld.assumed_share >= ld.design_share - 1e-12
    share = (f"M g / {a.payload_share}" if assumed else f"{ld.design_share:.3f} M g")
    load_rows = []
    if len(set(ld.rope_lengths)) > 1:
        load_rows.append(("rope lengths (team order)", f"{each(ld.rope_lengths)} m"))
    load_rows += [
        ("payload at rest: depth below the vehicles", val(ld.hang_depth, "m")),
        ("  offset from the centroid (x, y)", f"{each(ld.payload_offset)} m"),
        ("  rope tension per vehicle (team order)", f"{each(ld.tension)} N"),
        ("  share of the payload per vehicle", each(ld.share)),
        (f"worst share, vehicles within {ld.position_error:g} m of their places "
         f"(vehicle {ld.worst_vehicle})", each((ld.worst_share,))),
        ("  its vertical load", val(ld.worst_vertical_load, "N")),
        (f"design share: the larger of assumed 1/{a.payload_share} and at rest"
         if not ld.design_basis else "design share: the worst share (load sharing not "
         "relied on)", each((ld.design_share,))),
        (f"share accelerating at limits.accel_norm {ld.accel:g} m/s^2 "
         f"(vehicle {ld.accel_vehicle})", each((ld.accel_share,))),
        ("  its largest rope tension", val(ld.accel_tension, "N")),
    ]
    load_text = (f"(m + M/{a.payload_share}) g" if assumed
                 else f"(m + {ld.design_share:.3f} M) g")
    rows = [
        ("equilibrium rope tension (eq. T)", val(a.equilibrium_tension, "N")),
        ("  rope angle from vertical", val(a.equilibrium_rope_angle, "rad")),
        *load_rows,
        (f"vertical load per vehicle {load_text}", val(a.vertical_load, "N")),
        ("largest tilt arccos(load / thrust ref.)", val(a.max_tilt, "rad")),
        ("bank limit", val(a.bank_limit, "rad")),
        ("horizontal force at the bank limit", val(a.horizontal_force, "N")),
        (f"rope pull (eq. Th) at nominal ||z2|| = {a.nominal_span:.3f} m",
         val(a.rope_pull_nominal, "N")),
        (f"rope pull (eq. Th) at design ||z2|| = {a.design_span:.3f} m",
         val(a.rope_pull_design, "N")),
        (f"rope pull (eq. Th) at ||z2|| = {a.worst_edge:.3f} m (eq. max worst edge)",
         val(a.rope_pull_worst_edge, "N")),
        (f"  {share} = {a.rope_pull_bound:.3f} N holds at ||z2|| = l sqrt 2",
         val(a.rope_pull_bound_span, "m")),
        ("largest guidance acceleration (F_h - T_h) / m", val(a.max_accel, "m/s^2")),
        ("  per-axis limit", val(a.max_accel_axis, "m/s^2")),
    ]
    k = a.gain_coefficients
    rows += [
        (f"eq. max: c1 ||e_v|| = {k['c1']:g} * {k['speed_error_m_s']:g}",
         val(a.gain_terms["c1_speed"], "m/s^2")),
        (f"       + c2 e_max kappa = {k['c2']:g} * {k['distance_error_m']:g} * {k['kappa']:.3f}",
         val(a.gain_terms["c2_distance"], "m/s^2")),
        (f"       + mu_r ||z||max = {k['mu_r']:g} * {k['worst_edge_m']:.3f}",
         val(a.gain_terms["mu_rotation"], "m/s^2")),
        ("       = left side", val(a.gain_lhs, "m/s^2")),
        (f"       {'<=' if a.gain_lhs <= a.max_accel_axis else '>'} per-axis limit",
         val(a.max_accel_axis, "m/s^2")),
        ("largest safe distance between opposite vehicles", val(a.safe_span, "m")),
        ("maximum safe deformation (beyond the nominal shape)", val(a.safe_deformation, "m")),
        (f"shape's weakest mode: stiffness {a.shape_hold.stiffness:.3g}, its distance error "
         f"under {a.shape_hold.disturbance:g} m/s^2", val(a.shape_hold.drift_error, "m")),
        ("scales of the shape the GCS flies",
         f"{a.scale_min_flown:.3f} to {a.scale_max_flown:.3f}"),
        ("largest payload the team can carry", val(a.largest_payload, "kg")),
        (f"lift altitude (ceiling {a.lift_ceiling:.3f} m)", val(a.lift_altitude, "m")),
    ]
    width = max(len(r[0]) for r in rows)
    lines = [f"worst-case analysis of {a.team} ({a.vehicles} vehicles) from {source}"]
    lines += [f"  {name:<{width}}  {value}" for name, value in rows]
    lines += [f"warning: {w}" for w in a.warnings]
    lines += [f"VIOLATION {v.term}: {v.message}" for v in a.violations]
    lines.append("result: OK" if a.ok else f"result: FAILED ({len(a.violations)} violation(s))")
    return "\n".join(lines)


def analysis_json(a: Analysis) -> str:
    """The analysis as one line of JSON."""
    return json.dumps(a.to_json(), sort_keys=False)
