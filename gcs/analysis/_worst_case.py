"""Force and worst-case analysis of a team (paper, section "Force and worst case").

Everything is computed from the team config with the paper's formulas,
generalised from the square to any rigid team:

* eq. T, rope tension at equilibrium with the payload under the centroid:
  ``(M g / n) l / sqrt(l^2 - r^2)``, r the vehicle's horizontal distance to the
  payload (``d2 / 2`` for the square);
* the vertical load of a vehicle carrying a conservative share of the payload,
  ``(m + M / share) g`` (share = n - 1: a third for four vehicles), the largest
  tilt ``arccos(load / thrust_reference)`` and the horizontal force left at the
  bank limit ``thrust_reference * sin(bank)``;
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
  vehicle to payload, so F_h - T_h(r) >= m a_max bounds r.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field

import numpy as np

from gcs.config import Team
from gcs.formation import motion_basis

__all__ = ["GAIN_FIELDS", "Analysis", "Violation", "a_safe_span", "analysis_json", "analyze",
           "format_report",
           "gain_violation", "rope_pull"]

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
    """Result of :func:`analyze`; see ``to_json`` for the stable key names (SI units)."""

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
    violations: tuple[Violation, ...] = field(default=())
    warnings: tuple[str, ...] = field(default=())

    @property
    def ok(self) -> bool:
        """True when no term is violated."""
        return not self.violations

    def to_json(self) -> dict[str, object]:
        """One JSON-ready object with stable keys (documented in README)."""

        def num(x: float) -> float | None:
            return None if not math.isfinite(x) else round(float(x), 6)

        return {
            "team": self.team,
            "vehicles": self.vehicles,
            "gravity_m_s2": num(self.gravity),
            "payload_share": self.payload_share,
            "equilibrium_tension_N": num(self.equilibrium_tension),
            "equilibrium_rope_angle_rad": num(self.equilibrium_rope_angle),
            "vertical_load_N": num(self.vertical_load),
            "max_tilt_rad": num(self.max_tilt),
            "bank_limit_rad": num(self.bank_limit),
            "horizontal_force_N": num(self.horizontal_force),
            "rope_pull": {
                "nominal_span_m": num(self.nominal_span),
                "nominal_N": num(self.rope_pull_nominal),
                "design_rope_angle_rad": num(self.design_rope_angle),
                "design_span_m": num(self.design_span),
                "design_N": num(self.rope_pull_design),
                "bound_N": num(self.rope_pull_bound),
                "bound_span_m": num(self.rope_pull_bound_span),
                "worst_edge_m": num(self.worst_edge),
                "worst_edge_N": num(self.rope_pull_worst_edge),
            },
            "max_guidance_accel_m_s2": num(self.max_accel),
            "max_guidance_accel_axis_m_s2": num(self.max_accel_axis),
            "gain_condition": {
                "terms_m_s2": {k: num(v) for k, v in self.gain_terms.items()},
                "coefficients": {k: num(v) for k, v in self.gain_coefficients.items()},
                "lhs_m_s2": num(self.gain_lhs),
                "rhs_m_s2": num(self.max_accel_axis),
                "ok": self.gain_lhs <= self.max_accel_axis,
            },
            "configured_limits": {
                "accel_norm_m_s2": num(self.configured_accel_norm),
                "accel_axis_m_s2": num(self.configured_accel_axis),
            },
            "safe_deformation": {
                "span_m": num(self.safe_span),
                "margin_m": num(self.safe_deformation),
            },
            "violations": [asdict(v) for v in self.violations],
            "warnings": list(self.warnings),
            "ok": self.ok,
        }


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


def analyze(team: Team) -> Analysis:
    """Run the worst-case analysis of a loaded team."""
    cfg = team.config
    f = team.formation
    g = cfg.analysis.gravity
    n = f.n
    m = cfg.airframe.mass
    M = cfg.payload.mass
    l = cfg.payload.rope_length
    share = cfg.analysis.payload_share or max(n - 1, 1)
    violations: list[Violation] = []
    warnings: list[str] = []

    r_nom = float(f.radii.max())
    if r_nom >= l:
        violations.append(Violation("payload.rope_length", f"ropes of {l:g} m cannot reach the "
                                    f"centroid from {_n(r_nom)} m away"))
        tension = eq_angle = math.inf
    else:
        tension = (M * g / n) * l / math.sqrt(l**2 - r_nom**2)
        eq_angle = math.asin(r_nom / l)

    load = (m + M / share) * g
    thrust_ref = cfg.airframe.thrust_reference
    if load >= thrust_ref:
        violations.append(Violation("airframe.thrust_reference",
                                    f"vertical load {_n(load, 2)} N is not below the reference "
                                    f"thrust {_n(thrust_ref, 2)} N: the vehicle cannot carry "
                                    f"its share"))
        max_tilt = 0.0
    else:
        max_tilt = math.acos(load / thrust_ref)
    thrust_max = cfg.airframe.thrust_max
    if load >= thrust_max:
        violations.append(Violation("airframe.thrust_max",
                                    f"vertical load {_n(load, 2)} N is not below the full-speed "
                                    f"thrust {thrust_max:.3g} N (4 x thrust_coefficient x "
                                    f"rotor_speed_max^2): the vehicle cannot lift itself and "
                                    f"its share of the payload"))
    bank = cfg.limits.bank
    if bank >= max_tilt:
        tilt_deg = math.degrees(max_tilt)
        violations.append(Violation("limits.bank_deg",
                                    f"bank limit {_n(bank)} rad is not below the largest tilt "
                                    f"{_n(max_tilt)} rad that still carries {_n(load, 2)} N: set "
                                    f"it below {_floor3(tilt_deg)} degrees",
                                    {"limits.bank_deg": tilt_deg}))
    f_h = thrust_ref * math.sin(bank)

    weight_share = M * g / share
    theta = math.radians(cfg.analysis.design_rope_angle_deg)
    design_span = 2.0 * l * math.sin(theta)
    t_design = rope_pull(weight_share, l, design_span)
    if design_span < 2 * r_nom:
        warnings.append(f"the design rope angle {_n(theta)} rad is below the rope angle of the "
                        f"nominal shape {_n(eq_angle)} rad")
    max_accel = (f_h - t_design) / m
    max_axis = max_accel * _AXIS_FACTOR
    if max_accel <= 0:
        violations.append(Violation("analysis.design_rope_angle_deg",
                                    f"the rope pull {_n(t_design, 2)} N at the design angle "
                                    f"exceeds the horizontal force {_n(f_h, 2)} N left at the "
                                    f"bank limit"))

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
    if lhs > max_axis:
        violations.append(gain_violation(terms, {"c1_speed": ev_max,
                                                 "c2_distance": e_max * kappa,
                                                 "mu_rotation": worst_edge}, max_axis))
    if cfg.limits.accel_norm > max_accel:
        violations.append(Violation("limits.accel_norm",
                                    f"{cfg.limits.accel_norm:g} m/s^2 exceeds the largest "
                                    f"guidance acceleration {_n(max_accel)} m/s^2: set it to "
                                    f"at most {_floor3(max_accel)}",
                                    {"limits.accel_norm": max_accel}))
    if cfg.limits.accel_axis > max_axis:
        violations.append(Violation("limits.accel_axis",
                                    f"{cfg.limits.accel_axis:g} m/s^2 exceeds the per-axis "
                                    f"limit {_n(max_axis)} m/s^2: set it to at most "
                                    f"{_floor3(max_axis)}", {"limits.accel_axis": max_axis}))

    # Largest vehicle-payload distance that leaves the configured acceleration available.
    safe_span = a_safe_span(f_h, m, cfg.limits.accel_norm, weight_share, l)
    safe_margin = safe_span - 2 * r_nom
    if safe_margin <= 0 and not violations:
        violations.append(Violation("limits.accel_norm",
                                    "the nominal shape already pulls the ropes too hard "
                                    "to leave the configured acceleration"))
    if e_max > safe_margin > 0:
        warnings.append(f"eq. max assumes distance errors up to {_n(e_max, 2)} m, beyond the "
                        f"safe deformation of {_n(safe_margin)} m")

    return Analysis(
        team=cfg.name, vehicles=n, gravity=g, payload_share=share,
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
        violations=tuple(violations), warnings=tuple(warnings),
    )


def format_report(a: Analysis, source: str) -> str:
    """Human-readable table of the analysis."""

    def val(x: float, unit: str, digits: int = 3) -> str:
        return "unreachable" if not math.isfinite(x) else f"{_n(x, digits)} {unit}"

    share = f"M g / {a.payload_share}"
    rows = [
        ("equilibrium rope tension (eq. T)", val(a.equilibrium_tension, "N")),
        ("  rope angle from vertical", val(a.equilibrium_rope_angle, "rad")),
        (f"vertical load per vehicle (m + M/{a.payload_share}) g", val(a.vertical_load, "N")),
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
