"""What the analysis certifies: its figures, the conditions a config breaks, its warnings.

The data only: :mod:`gcs.analysis._worst_case` computes it, :mod:`._report` prints it for
a person and :mod:`._json` for a program, so that neither output can drift from the
other's figures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from gcs.analysis._json import analysis_object
from gcs.analysis._shape_hold import ShapeHold

__all__ = ["Analysis", "StaticShares", "Violation"]


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
    (:func:`.accelerating_share`; a shape shrunk below 1 loads one vehicle more)."""
    accel_vehicle: int = 0
    accel_tension: float = math.nan
    """The largest rope tension then, N."""


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
    """The smallest scale the GCS flies (:func:`._scales.flown_scale_min`)."""
    scale_max_flown: float
    """The largest scale the GCS flies (:func:`._scales.flown_scale_max`)."""
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
        return analysis_object(self)
