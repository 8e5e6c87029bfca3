"""The certificate as a table for a person (``gcs analyze``): each figure on its own row,
named by the paper's equation it comes from, then the warnings, the violations and the
result.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from gcs.analysis._figures import fmt

if TYPE_CHECKING:
    from gcs.analysis._certificate import Analysis

__all__ = ["format_report"]

_Row = tuple[str, str]


def format_report(a: Analysis, source: str) -> str:
    """Human-readable table of the analysis."""
    rows = [*_force_rows(a), *_gain_rows(a), *_envelope_rows(a)]
    width = max(len(r[0]) for r in rows)
    lines = [f"worst-case analysis of {a.team} ({a.vehicles} vehicles) from {source}"]
    lines += [f"  {name:<{width}}  {value}" for name, value in rows]
    lines += [f"warning: {w}" for w in a.warnings]
    lines += [f"VIOLATION {v.term}: {v.message}" for v in a.violations]
    lines.append("result: OK" if a.ok else f"result: FAILED ({len(a.violations)} violation(s))")
    return "\n".join(lines)


def _val(x: float, unit: str, digits: int = 3) -> str:
    return "unreachable" if not math.isfinite(x) else f"{fmt(x, digits)} {unit}"


def _each(xs: tuple[float, ...], digits: int = 3) -> str:
    return " ".join("-" if not math.isfinite(x) else f"{round(x, digits) + 0.0:.{digits}f}"
                    for x in xs)


def _assumed(a: Analysis) -> bool:
    """Whether the force chain designs for the assumed share 1/payload_share."""
    return a.load.assumed_share >= a.load.design_share - 1e-12


def _load_rows(a: Analysis) -> list[_Row]:
    """Where the payload hangs and each vehicle's share of it."""
    ld = a.load
    rows = []
    if len(set(ld.rope_lengths)) > 1:
        rows.append(("rope lengths (team order)", f"{_each(ld.rope_lengths)} m"))
    rows += [
        ("payload at rest: depth below the vehicles", _val(ld.hang_depth, "m")),
        ("  offset from the centroid (x, y)", f"{_each(ld.payload_offset)} m"),
        ("  rope tension per vehicle (team order)", f"{_each(ld.tension)} N"),
        ("  share of the payload per vehicle", _each(ld.share)),
        (f"worst share, vehicles within {ld.position_error:g} m of their places "
         f"(vehicle {ld.worst_vehicle})", _each((ld.worst_share,))),
        ("  its vertical load", _val(ld.worst_vertical_load, "N")),
        (f"design share: the larger of assumed 1/{a.payload_share} and at rest"
         if not ld.design_basis else "design share: the worst share (load sharing not "
         "relied on)", _each((ld.design_share,))),
        (f"share accelerating at limits.accel_norm {ld.accel:g} m/s^2 "
         f"(vehicle {ld.accel_vehicle})", _each((ld.accel_share,))),
        ("  its largest rope tension", _val(ld.accel_tension, "N")),
    ]
    return rows


def _force_rows(a: Analysis) -> list[_Row]:
    """Eq. T, the vertical load, the tilt and eq. Th down to the largest acceleration."""
    assumed = _assumed(a)
    design = a.load.design_share
    share = f"M g / {a.payload_share}" if assumed else f"{design:.3f} M g"
    load_text = f"(m + M/{a.payload_share}) g" if assumed else f"(m + {design:.3f} M) g"
    return [
        ("equilibrium rope tension (eq. T)", _val(a.equilibrium_tension, "N")),
        ("  rope angle from vertical", _val(a.equilibrium_rope_angle, "rad")),
        *_load_rows(a),
        (f"vertical load per vehicle {load_text}", _val(a.vertical_load, "N")),
        ("largest tilt arccos(load / thrust ref.)", _val(a.max_tilt, "rad")),
        ("bank limit", _val(a.bank_limit, "rad")),
        ("horizontal force at the bank limit", _val(a.horizontal_force, "N")),
        (f"rope pull (eq. Th) at nominal ||z2|| = {a.nominal_span:.3f} m",
         _val(a.rope_pull_nominal, "N")),
        (f"rope pull (eq. Th) at design ||z2|| = {a.design_span:.3f} m",
         _val(a.rope_pull_design, "N")),
        (f"rope pull (eq. Th) at ||z2|| = {a.worst_edge:.3f} m (eq. max worst edge)",
         _val(a.rope_pull_worst_edge, "N")),
        (f"  {share} = {a.rope_pull_bound:.3f} N holds at ||z2|| = l sqrt 2",
         _val(a.rope_pull_bound_span, "m")),
        ("largest guidance acceleration (F_h - T_h) / m", _val(a.max_accel, "m/s^2")),
        ("  per-axis limit", _val(a.max_accel_axis, "m/s^2")),
    ]


def _gain_rows(a: Analysis) -> list[_Row]:
    """Eq. max term by term, against the per-axis limit."""
    k = a.gain_coefficients
    return [
        (f"eq. max: c1 ||e_v|| = {k['c1']:g} * {k['speed_error_m_s']:g}",
         _val(a.gain_terms["c1_speed"], "m/s^2")),
        (f"       + c2 e_max kappa = {k['c2']:g} * {k['distance_error_m']:g} * {k['kappa']:.3f}",
         _val(a.gain_terms["c2_distance"], "m/s^2")),
        (f"       + mu_r ||z||max = {k['mu_r']:g} * {k['worst_edge_m']:.3f}",
         _val(a.gain_terms["mu_rotation"], "m/s^2")),
        ("       = left side", _val(a.gain_lhs, "m/s^2")),
        (f"       {'<=' if a.gain_lhs <= a.max_accel_axis else '>'} per-axis limit",
         _val(a.max_accel_axis, "m/s^2")),
    ]


def _envelope_rows(a: Analysis) -> list[_Row]:
    """What the certificate allows: the deformation, the scales, the payload, the lift."""
    return [
        ("largest safe distance between opposite vehicles", _val(a.safe_span, "m")),
        ("maximum safe deformation (beyond the nominal shape)",
         _val(a.safe_deformation, "m")),
        (f"shape's weakest mode: stiffness {a.shape_hold.stiffness:.3g}, its distance error "
         f"under {a.shape_hold.disturbance:g} m/s^2", _val(a.shape_hold.drift_error, "m")),
        ("scales of the shape the GCS flies",
         f"{a.scale_min_flown:.3f} to {a.scale_max_flown:.3f}"),
        ("largest payload the team can carry", _val(a.largest_payload, "kg")),
        (f"lift altitude (ceiling {a.lift_ceiling:.3f} m)",
         _val(a.lift_altitude, "m")),
    ]
