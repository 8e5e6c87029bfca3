"""The certificate as JSON for a program (``gcs analyze --json``): stable keys with their
SI units in the names, documented in docs/analysis.md ("``--json``").

A figure that is not finite (a rope that cannot reach, ropes that cannot hang the
payload) is null: JSON has no inf or NaN.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from gcs.analysis._certificate import Analysis, StaticShares

__all__ = ["analysis_json", "analysis_object"]


def analysis_json(a: Analysis) -> str:
    """The analysis as one line of JSON."""
    return json.dumps(a.to_json(), sort_keys=False)


def analysis_object(a: Analysis) -> dict[str, object]:
    """One JSON-ready object with the analysis' stable keys."""
    return {
        "team": a.team,
        "vehicles": a.vehicles,
        "gravity_m_s2": _num(a.gravity),
        "payload_share": a.payload_share,
        "equilibrium_tension_N": _num(a.equilibrium_tension),
        "equilibrium_rope_angle_rad": _num(a.equilibrium_rope_angle),
        "vertical_load_N": _num(a.vertical_load),
        "max_tilt_rad": _num(a.max_tilt),
        "bank_limit_rad": _num(a.bank_limit),
        "horizontal_force_N": _num(a.horizontal_force),
        "rope_pull": _rope_pull(a),
        "max_guidance_accel_m_s2": _num(a.max_accel),
        "max_guidance_accel_axis_m_s2": _num(a.max_accel_axis),
        "gain_condition": _gain_condition(a),
        "configured_limits": {
            "accel_norm_m_s2": _num(a.configured_accel_norm),
            "accel_axis_m_s2": _num(a.configured_accel_axis),
        },
        "safe_deformation": {
            "span_m": _num(a.safe_span),
            "margin_m": _num(a.safe_deformation),
        },
        "static_load": _static_load(a.load),
        "largest_payload_kg": _num(a.largest_payload),
        "lift": {"altitude_m": _num(a.lift_altitude),
                 "ceiling_m": _num(a.lift_ceiling)},
        "scales_flown": {"min": _num(a.scale_min_flown),
                         "max": _num(a.scale_max_flown)},
        "shape_hold": {
            "weakest_stiffness": _num(a.shape_hold.stiffness),
            "disturbance_m_s2": _num(a.shape_hold.disturbance),
            "drift_error_m": _num(a.shape_hold.drift_error),
            "new_edges": [list(e) for e in a.shape_hold.new_edges],
            "new_stiffness": _num(a.shape_hold.new_stiffness),
        },
        "violations": [asdict(v) for v in a.violations],
        "warnings": list(a.warnings),
        "ok": a.ok,
    }


def _rope_pull(a: Analysis) -> dict[str, object]:
    """Eq. Th at the shapes the certificate shows."""
    return {
        "nominal_span_m": _num(a.nominal_span),
        "nominal_N": _num(a.rope_pull_nominal),
        "design_rope_angle_rad": _num(a.design_rope_angle),
        "design_span_m": _num(a.design_span),
        "design_N": _num(a.rope_pull_design),
        "bound_N": _num(a.rope_pull_bound),
        "bound_span_m": _num(a.rope_pull_bound_span),
        "worst_edge_m": _num(a.worst_edge),
        "worst_edge_N": _num(a.rope_pull_worst_edge),
    }


def _gain_condition(a: Analysis) -> dict[str, object]:
    """Eq. max: its terms, what they are made of, and both sides."""
    return {
        "terms_m_s2": {k: _num(v) for k, v in a.gain_terms.items()},
        "coefficients": {k: _num(v) for k, v in a.gain_coefficients.items()},
        "lhs_m_s2": _num(a.gain_lhs),
        "rhs_m_s2": _num(a.max_accel_axis),
        "ok": a.gain_lhs <= a.max_accel_axis,
    }


def _static_load(ld: StaticShares) -> dict[str, object]:
    """The payload's load on each vehicle (per-vehicle lists in team order)."""
    return {
        "rope_lengths_m": _nums(ld.rope_lengths),
        "taut": list(ld.taut),
        "tension_N": _nums(ld.tension),
        "vertical_N": _nums(ld.vertical),
        "horizontal_N": _nums(ld.horizontal),
        "share": _nums(ld.share),
        "payload_offset_m": _nums(ld.payload_offset),
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
                                else _nums(ld.even_rope_lengths)),
        "accel_m_s2": _num(ld.accel),
        "accel_share": _num(ld.accel_share),
        "accel_vehicle": ld.accel_vehicle,
        "accel_tension_N": _num(ld.accel_tension),
    }


def _num(x: float) -> float | None:
    return None if not math.isfinite(x) else round(float(x), 6) + 0.0


def _nums(xs: tuple[float, ...]) -> list[float | None]:
    return [_num(x) for x in xs]
