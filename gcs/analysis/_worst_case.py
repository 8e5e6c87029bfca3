"""Force and worst-case analysis of a team (paper, section "Force and worst case"): the
certificate's computation, step by step.

Everything is computed from the team config with the paper's formulas, generalised from
the square to any rigid team, with the payload's share per vehicle taken from the
geometry. Each step is a module of its own:

* the share each vehicle carries at rest, off its place and accelerating, and the share
  the force chain designs for (:mod:`._shares`), over the scales the GCS flies
  (:mod:`._scales`);
* the force chain: eq. T, Th, the largest guidance acceleration and the largest safe
  deformation (:mod:`._forces`);
* eq. max's left side (:mod:`._gain_condition`);
* the largest payload the team can carry, named as a fix wherever the payload breaks a
  condition (:mod:`._largest_payload`);
* the lift, under ``operator.altitude_max`` and the geofence (:mod:`._lift`);
* the shape's weakest deformation mode (:mod:`._shape_hold`): the distance error an
  unseen ``analysis.disturbance_accel`` per vehicle holds it at, within the safe
  deformation, or the distance gain and the edges that bring it there.

What a config breaks is worded in :mod:`._violations`, what it should know in
:mod:`._warnings`; the result (:class:`.Analysis`) is printed by :mod:`._report` and
:mod:`._json`.
"""

from __future__ import annotations

import collections
import dataclasses
import threading
from dataclasses import dataclass

from gcs.analysis._certificate import Analysis, StaticShares, Violation
from gcs.analysis._forces import Chain, RopePulls, chain, rope_pulls
from gcs.analysis._gain_condition import GainCondition, gain_condition
from gcs.analysis._largest_payload import largest_payload
from gcs.analysis._lift import Lift, lift
from gcs.analysis._scales import flown_scale_max, flown_scale_min
from gcs.analysis._shape_hold import ShapeHold, shape_hold
from gcs.analysis._shares import (
    designed_for_worst,
    desired_shares,
    flown_shares,
    no_shares,
    rest_ropes,
)
from gcs.analysis._violations import (
    CHECKED_TEAM_SIZE,
    acceleration_violations,
    hold_violation,
    lift_violation,
    lighter_payload,
    nominal_shape_violation,
    rope_violation,
    size_violation,
    thrust_violations,
)
from gcs.analysis._warnings import (
    distance_error_warnings,
    load_warnings,
    motion_warnings,
    rope_angle_warnings,
    scale_min_warnings,
)
from gcs.config import Team, TeamConfig
from gcs.formation import motion_basis

__all__ = ["analyze"]

_ANALYSES: collections.OrderedDict[TeamConfig, Analysis] = collections.OrderedDict()
_ANALYSES_KEPT = 32
"""Analyses kept by config value: a process that loads the same file again (a test
suite's worker, flights of many seeds) asks for the same analysis."""
_ANALYSES_LOCK = threading.Lock()


def analyze(team: Team) -> Analysis:
    """Run the worst-case analysis of a loaded team.

    Once per team (its cost: docs/performance.md): a loaded team is frozen, its analysis
    a function of its config alone, and the command line, the scenario check and the GCS
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


@dataclass(frozen=True)
class _Design:
    """The share the force chain designs for, its chain, and the scales flown with it."""

    load: StaticShares | None
    """The payload's load on each vehicle (None: the ropes cannot hang it)."""
    unreachable: str | None
    """Why the ropes cannot hang the payload (None: they can)."""
    share: float
    chain: Chain
    scale_min: float
    scale_max: float
    warnings: tuple[str, ...]
    """What the shares and scales warn of."""

    @property
    def worst_share(self) -> float:
        """The worst share within ``analysis.position_error`` (the design share when the
        ropes cannot hang the payload)."""
        return self.load.worst_share if self.load is not None else self.share


def _design(team: Team, assumed: float) -> _Design:
    """The design share: the larger of ``assumed`` and the share at rest, or the worst share
    over the scales flown where nothing holds the split at it (its chain's safe span then
    caps the largest scale); with what the shares and the scales warn of."""
    cfg = team.config
    mass = cfg.payload.mass
    at_rest, unreachable = desired_shares(team, assumed)
    if at_rest is None:
        c = chain(team, mass, assumed)
        return _Design(None, unreachable, assumed, c, cfg.guidance.scale_min,
                       flown_scale_max(team, c.safe_span), ())
    c = chain(team, mass, at_rest.design_share)
    largest = flown_scale_max(team, c.safe_span)
    smallest = flown_scale_min(team)
    flown = tuple(sorted({smallest.scale, 1.0, largest}))
    ld = designed_for_worst(team, flown_shares(team, at_rest, flown))
    if ld.design_basis:
        c = chain(team, mass, ld.design_share)
        largest = min(largest, flown_scale_max(team, c.safe_span))
    warnings = (*scale_min_warnings(team, smallest), *load_warnings(team, ld, flown))
    return _Design(ld, None, ld.design_share, c, smallest.scale, largest, warnings)


def _heaviest(team: Team, design: _Design, gain_lhs: float, settle: bool) -> float:
    """The largest payload the team carries at the design's shares (:func:`largest_payload`),
    settled at its own scales when it is lighter than the configured one and ``settle``."""
    heaviest = largest_payload(team, design.share, gain_lhs, design.worst_share)
    if settle and 0.0 < heaviest < team.config.payload.mass:
        return _settled_payload(team, heaviest)
    return heaviest


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


def _violations(team: Team, design: _Design, gains: GainCondition, heaviest: float,
                pulls: RopePulls, hold: ShapeHold, lifted: Lift) -> list[Violation]:
    """Every condition the config breaks, in the order they are reported: the team's size
    first, the force chain's, the shape's, the lift."""
    cfg = team.config
    c = design.chain
    lighter = lighter_payload(heaviest, cfg.payload.mass)
    out = [] if design.unreachable is None else [rope_violation(design.unreachable)]
    out += thrust_violations(cfg, c, design.share, design.worst_share, lighter)
    out += acceleration_violations(cfg, c, gains, lighter)
    if c.safe_margin <= 0 and not out:
        left = (c.horizontal_force - pulls.nominal) / cfg.airframe.mass
        out.append(nominal_shape_violation(left, lighter))
    if c.safe_margin > 0 and hold.drift_error > c.safe_margin:
        out.append(hold_violation(team, hold, c.safe_margin, gains.c2_room(c.max_axis)))
    if team.formation.n > CHECKED_TEAM_SIZE:
        out.insert(0, size_violation(team.formation.n))
    too_high = lift_violation(cfg, lifted)
    return out if too_high is None else [*out, too_high]


def _analyze(team: Team, *, settle: bool = True) -> Analysis:
    """The analysis of ``team``: the design share and its force chain, eq. max, the largest
    payload, then what they break and warn of (``settle``: :func:`_settled_payload`)."""
    cfg = team.config
    share_div = cfg.analysis.payload_share or max(team.formation.n - 1, 1)
    basis = motion_basis(team.formation)
    gains = gain_condition(team, basis.rotate)
    design = _design(team, 1.0 / share_div)
    c = design.chain
    heaviest = _heaviest(team, design, gains.lhs, settle)
    pulls = rope_pulls(team, c.weight_share, gains.worst_edge)
    hold = shape_hold(team.formation, cfg.guidance.c2, cfg.analysis.disturbance_accel,
                      c.safe_margin)
    lifted = lift(team)
    tension, rope_angle = rest_ropes(design.load)
    warnings = (*motion_warnings(basis.unavailable, gains.mu_r), *design.warnings,
                *rope_angle_warnings(pulls.design_angle, rope_angle),
                *distance_error_warnings(gains.distance_error, c.safe_margin))
    violations = _violations(team, design, gains, heaviest, pulls, hold, lifted)
    return Analysis(
        team=cfg.name, vehicles=team.formation.n, gravity=cfg.analysis.gravity,
        payload_share=share_div, equilibrium_tension=tension, equilibrium_rope_angle=rope_angle,
        vertical_load=c.load, max_tilt=c.max_tilt, bank_limit=cfg.limits.bank,
        horizontal_force=c.horizontal_force, nominal_span=pulls.nominal_span,
        rope_pull_nominal=pulls.nominal, design_rope_angle=pulls.design_angle,
        design_span=pulls.design_span, rope_pull_design=c.rope_pull_design,
        rope_pull_bound=c.weight_share, rope_pull_bound_span=pulls.bound_span,
        worst_edge=pulls.worst_edge, rope_pull_worst_edge=pulls.at_worst_edge,
        max_accel=c.max_accel, max_accel_axis=c.max_axis, gain_terms=gains.terms,
        gain_coefficients=gains.coefficients(), gain_lhs=gains.lhs,
        configured_accel_norm=cfg.limits.accel_norm,
        configured_accel_axis=cfg.limits.accel_axis,
        safe_span=c.safe_span, safe_deformation=c.safe_margin,
        load=design.load if design.load is not None else no_shares(
            cfg.payload.lengths(team.formation.n), 1.0 / share_div),
        largest_payload=heaviest, lift_altitude=lifted.top, lift_ceiling=lifted.ceiling,
        scale_min_flown=design.scale_min, scale_max_flown=design.scale_max, shape_hold=hold,
        violations=tuple(violations), warnings=warnings,
    )
