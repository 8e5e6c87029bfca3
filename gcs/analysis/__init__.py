"""The paper's force and worst-case analysis of a team: a safety certificate.

:func:`analyze` checks that the guidance can never ask more than the airframes
give (eq. T, Th and max of the paper) and finds the largest safe deformation;
``gcs analyze`` prints it, and a team that fails it is not flown. The share of the
payload each vehicle carries comes from the geometry (:func:`static_load`): where
the payload hangs under the desired shape, which ropes are slack, each rope's
tension, and the worst share with the vehicles off their places.

Modules (the maths first, then the words and the outputs):

    ``_worst_case``      The certificate's computation (:func:`analyze`): its steps in
                         order, each from the modules below (paper, section "Force and
                         worst case").
    ``_certificate``     What it certifies: the figures, violations and warnings
                         (:class:`Analysis`, :class:`StaticShares`, ``Violation``).
    ``_forces``          The paper's force chain: eq. T, Th, the largest acceleration and
                         the safe span, for one payload share.
    ``_gain_condition``  Eq. max's left side: the guidance's worst demand on one axis.
    ``_shares``          The share of the payload each vehicle carries, as the analysis
                         designs for it: at rest, off its place, accelerating.
    ``_scales``          The scales of the shape the GCS flies.
    ``_largest_payload`` The largest payload the team can carry.
    ``_lift``            The lift: where the payload leaves the ground, the altitude it
                         climbs to, the ceiling.
    ``_safe_guidance``   The guidance config the GCS flies: the scale capped at the safe
                         deformation.
    ``_shape_hold``      The shape's weakest deformation mode: how far an unseen
                         disturbance bends it under the guidance.
    ``_static_load``     The payload hanging at rest from its ropes: where it hangs, which
                         ropes pull, how hard.
    ``_team_load``       The payload's load on each vehicle of a team: at its desired
                         shape, at the worst shape within a deformation, accelerating with
                         the team, and the rope lengths that make every rope taut.
    ``_violations``      The wording of the conditions a config breaks, with their fixes.
    ``_warnings``        The wording of what the analysis warns of.
    ``_figures``         How a figure is printed in a message or the report.
    ``_report``          The certificate as a table (``gcs analyze``).
    ``_json``            The certificate as JSON (``gcs analyze --json``).
"""

from gcs.analysis._certificate import Analysis, StaticShares
from gcs.analysis._forces import a_safe_span
from gcs.analysis._json import analysis_json
from gcs.analysis._largest_payload import largest_payload
from gcs.analysis._report import format_report
from gcs.analysis._safe_guidance import safe_guidance
from gcs.analysis._shape_hold import ShapeHold, drift_error, shape_hold, weakest_mode
from gcs.analysis._static_load import (
    NoHangingPointError,
    StaticLoad,
    accelerating_load,
    hanging_point,
    static_load,
)
from gcs.analysis._team_load import (
    AcceleratingShare,
    WorstLoad,
    accelerating_share,
    desired_load,
    even_rope_lengths,
    hang_depth,
    worst_load,
)
from gcs.analysis._worst_case import analyze

__all__ = [
    "AcceleratingShare",
    "Analysis",
    "NoHangingPointError",
    "ShapeHold",
    "StaticLoad",
    "StaticShares",
    "WorstLoad",
    "a_safe_span",
    "accelerating_load",
    "accelerating_share",
    "analysis_json",
    "analyze",
    "desired_load",
    "drift_error",
    "even_rope_lengths",
    "format_report",
    "hang_depth",
    "hanging_point",
    "largest_payload",
    "safe_guidance",
    "shape_hold",
    "static_load",
    "weakest_mode",
    "worst_load",
]
