"""The wording of the conditions a config breaks, each with the fixes it names.

A violation says what is broken with its figures, and names each config field that
alone restores the condition with the value it needs: a lighter payload wherever the
payload breaks it (:func:`lighter_payload`), and never a negative limit or bank angle.
The figures are computed elsewhere (:mod:`gcs.analysis._forces`,
:mod:`gcs.analysis._gain_condition`, ...); here they are only compared and worded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gcs.analysis._certificate import Violation
from gcs.analysis._figures import floor3, fmt
from gcs.analysis._forces import Chain, vertical_load
from gcs.analysis._gain_condition import GainCondition
from gcs.analysis._lift import Lift
from gcs.analysis._shape_hold import ShapeHold
from gcs.config import Team, TeamConfig

__all__ = ["CHECKED_TEAM_SIZE", "GAIN_FIELDS", "LighterPayload", "acceleration_violations",
           "gain_violation", "hold_violation", "lift_violation", "lighter_payload",
           "limit_violation", "nominal_shape_violation", "rope_violation", "size_violation",
           "thrust_violations"]


@dataclass(frozen=True)
class LighterPayload:
    """The lighter payload a violation names as a fix (no fix when the configured payload
    is within what the team carries, or no payload is)."""

    mass: float
    fixes: dict[str, float]
    """``{"payload.mass": mass}``, or empty when there is no such fix."""

    def text(self, joint: str = "") -> str:
        """The fix as the tail of a message (``joint``: "or " beside another fix)."""
        return f"; {joint}carry at most {floor3(self.mass)} kg (payload.mass)" if self.fixes else ""


def lighter_payload(heaviest: float, mass: float) -> LighterPayload:
    """The fix of carrying ``heaviest`` kg instead of ``mass``, when it is a lighter one."""
    return LighterPayload(heaviest, {"payload.mass": heaviest} if 0.0 < heaviest < mass else {})


def rope_violation(unreachable: str) -> Violation:
    """Ropes that cannot hang the payload (``unreachable``: why)."""
    return Violation("payload.rope_length", f"the ropes cannot hang the payload: {unreachable}")


def thrust_violations(cfg: TeamConfig, c: Chain, design: float, worst_share: float,
                      lighter: LighterPayload) -> list[Violation]:
    """The vertical load against the reference and full-speed thrust, the largest tilt
    against the bank limit (``design``: the share the chain ``c`` is for)."""
    out = []
    thrust_ref, thrust_max = cfg.airframe.thrust_reference, cfg.airframe.thrust_max
    if c.load >= thrust_ref:
        out.append(Violation("airframe.thrust_reference",
                             f"vertical load {fmt(c.load, 2)} N ({design:.3f} of the payload) "
                             f"is not below the reference thrust {fmt(thrust_ref, 2)} N: the "
                             f"vehicle cannot carry its share{lighter.text()}", lighter.fixes))
    worst = vertical_load(cfg, worst_share, cfg.payload.mass)
    if c.load < thrust_max <= worst:
        out.append(Violation("airframe.thrust_max",
                             f"with the vehicles up to {cfg.analysis.position_error:g} m off "
                             f"their places, the vertical load {fmt(worst, 2)} N "
                             f"({worst_share:.3f} of the payload) is not below the full-speed "
                             f"thrust {thrust_max:.3g} N: the vehicle cannot hold its worst "
                             f"share{lighter.text()}", lighter.fixes))
    if c.load >= thrust_max:
        out.append(Violation("airframe.thrust_max",
                             f"vertical load {fmt(c.load, 2)} N is not below the full-speed "
                             f"thrust {thrust_max:.3g} N (4 x thrust_coefficient x "
                             f"rotor_speed_max^2): the vehicle cannot lift itself and its "
                             f"share of the payload{lighter.text()}", lighter.fixes))
    bank = cfg.limits.bank
    if 0.0 < c.max_tilt <= bank:
        tilt_deg = math.degrees(c.max_tilt)
        out.append(Violation("limits.bank_deg",
                             f"bank limit {fmt(bank)} rad is not below the largest tilt "
                             f"{fmt(c.max_tilt)} rad that still carries {fmt(c.load, 2)} N: set "
                             f"it below {floor3(tilt_deg)} degrees{lighter.text('or ')}",
                             {"limits.bank_deg": tilt_deg, **lighter.fixes}))
    return out


def acceleration_violations(cfg: TeamConfig, c: Chain, gains: GainCondition,
                            lighter: LighterPayload) -> list[Violation]:
    """The acceleration the chain ``c`` leaves against the rope pull at the design angle,
    eq. max's left side and the configured limits."""
    out = []
    if c.max_accel <= 0:
        out.append(Violation("analysis.design_rope_angle_deg",
                             f"the rope pull {fmt(c.rope_pull_design, 2)} N at the design angle "
                             f"exceeds the horizontal force {fmt(c.horizontal_force, 2)} N left "
                             f"at the bank limit{lighter.text()}", lighter.fixes))
    if gains.lhs > c.max_axis > 0.0:  # none left at all: the limits' violations say so
        out.append(gain_violation(gains.terms, gains.per_unit(), c.max_axis))
    if cfg.limits.accel_norm > c.max_accel:
        out.append(limit_violation("limits.accel_norm", cfg.limits.accel_norm,
                                   "the largest guidance acceleration", c.max_accel, lighter))
    if cfg.limits.accel_axis > c.max_axis:
        out.append(limit_violation("limits.accel_axis", cfg.limits.accel_axis,
                                   "the per-axis limit", c.max_axis, lighter))
    return out


def limit_violation(name: str, value: float, what: str, largest: float,
                    lighter: LighterPayload) -> Violation:
    """A configured acceleration limit above what is left: the limit to set, when some is
    left, and the lighter payload (never a negative limit)."""
    if largest > 0.0:
        return Violation(name, f"{value:g} m/s^2 exceeds {what} {fmt(largest)} m/s^2: set it to "
                               f"at most {floor3(largest)}{lighter.text('or ')}",
                         {name: largest, **lighter.fixes})
    return Violation(name, f"{value:g} m/s^2 exceeds {what} {fmt(largest)} m/s^2: the rope pull "
                           f"leaves no acceleration at the bank limit{lighter.text()}",
                     lighter.fixes)


def nominal_shape_violation(left: float, lighter: LighterPayload) -> Violation:
    """No safe deformation: the nominal shape's rope pull already leaves less than the
    configured acceleration (``left``: what it leaves, m/s^2)."""
    fixes = {"limits.accel_norm": left, **lighter.fixes} if left > 0 else dict(lighter.fixes)
    named = [f"limits.accel_norm at most {floor3(left)}"] if left > 0 else []
    named += [f"payload.mass at most {floor3(lighter.mass)} kg"] if lighter.fixes else []
    return Violation("limits.accel_norm",
                     "the nominal shape already pulls the ropes too hard to leave the "
                     "configured acceleration" + (f": set {' or '.join(named)}" if named else ""),
                     fixes)


def lift_violation(cfg: TeamConfig, lift: Lift) -> Violation | None:
    """The lift climbing above its ceiling: the lift height that stays under it, the
    ceiling that clears it, or shorter ropes."""
    depth, top, ceiling = lift
    if depth is None or not top > ceiling:
        return None
    fixes = {"flight.lift_height": ceiling - depth} if ceiling > depth else {}
    lower = f"set flight.lift_height at most {floor3(ceiling - depth)}, or " if fixes else ""
    return Violation(
        "flight.lift_height",
        f"the payload leaves the ground with the vehicles at {fmt(depth)} m (at "
        f"guidance.scale_min {cfg.guidance.scale_min:g}), so lifting it "
        f"{cfg.flight.lift_height:g} m climbs to {fmt(top)} m, above the ceiling "
        f"{fmt(ceiling)} m (operator.altitude_max, safety.geofence_altitude): {lower}raise "
        f"both to at least {fmt(top)}, or shorten the ropes by {fmt(top - ceiling)} m",
        fixes)


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
    shown = " + ".join(f"{k} {fmt(t)}" for k, t in terms.items())
    head = (f"gain condition (eq. max) violated: {shown} = {fmt(lhs)} > {fmt(limit)} m/s^2 "
            f"by {fmt(excess)}")
    if not fixes:
        return Violation(" and ".join(GAIN_FIELDS.values()),
                         f"{head}; no gain alone can restore it: reduce several")
    alone = " or ".join(f"{name} <= {floor3(v)}" for name, v in fixes.items())
    cannot = [f"{GAIN_FIELDS[k]} (term {fmt(t)})" for k, t in terms.items()
              if GAIN_FIELDS[k] not in fixes]
    tail = f"; alone, not {', '.join(cannot)}" if cannot else ""
    return Violation(" or ".join(fixes), f"{head}; restored by {alone}{tail}", fixes)


CHECKED_TEAM_SIZE = 6
"""The largest team the analysis is checked on against the simulator (the hexagon). On
rings of twelve that it passed, the weakest mode's bound held neither the distance error
(1.0 to 2.1 m flown against 0.65 m bound, 0.79 m safe) nor load sharing the split
(docs/analysis.md): beyond it, ``gcs analyze --verify`` is the certificate."""


def size_violation(n: int) -> Violation:
    """A team larger than those the analysis is checked on: refused, with how to certify
    it by flying it."""
    return Violation(
        "vehicles",
        f"a team of {n} is beyond the {CHECKED_TEAM_SIZE} vehicles the analysis is checked on "
        f"in the simulator (a ring of twelve it passed flew 2.1 m of distance error against "
        f"0.79 m safe): `gcs analyze --verify` flies it, and --override-analysis flies it "
        f"once that passes")


def hold_violation(team: Team, hold: ShapeHold, safe: float, c2_room: float) -> Violation:
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
        f"square's is 2) holds the distance errors only within {fmt(hold.drift_error)} m "
        f"under an unseen {hold.disturbance:g} m/s^2 per vehicle "
        f"(analysis.disturbance_accel), beyond the safe deformation {fmt(safe)} m: "
        + (f"{gain}, or {edges}" if needed <= c2_room else f"{edges} ({gain})"),
        {"guidance.c2": needed} if needed <= c2_room else {})
