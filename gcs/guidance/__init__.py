"""The guidance law (eq. udi) and the worst-case analysis of a team.

:class:`Guidance` turns relative positions, own velocities and a motion demand
into one acceleration per vehicle (the compiled arithmetic is in ``_udi``);
:func:`analyze` is the paper's force and worst-case analysis (``gcs analyze``).

Modules:

    ``_analysis``  Force and worst-case analysis of a team (paper, section "Force and worst
                   case").
    ``_law``       Formation-motion guidance: eq. udi of the paper, per vehicle, from
                   relative data.
    ``_udi``       The guidance's per-vehicle arithmetic, compiled: eq. udi and its local
                   frames as loops.
"""

from gcs.guidance._analysis import (
    GAIN_FIELDS,
    Analysis,
    Violation,
    a_safe_span,
    analysis_json,
    analyze,
    format_report,
    gain_violation,
    rope_pull,
)
from gcs.guidance._law import (
    Guidance,
    MotionDemand,
    RelativeMeasurements,
    formation_acceleration,
    relative_measurements,
    saturate,
)
from gcs.guidance._udi import finite_max_norm, local_frames, to_ned_saturated, udi

__all__ = [
    "GAIN_FIELDS",
    "Analysis",
    "Guidance",
    "MotionDemand",
    "RelativeMeasurements",
    "Violation",
    "a_safe_span",
    "analysis_json",
    "analyze",
    "finite_max_norm",
    "format_report",
    "formation_acceleration",
    "gain_violation",
    "local_frames",
    "relative_measurements",
    "rope_pull",
    "saturate",
    "to_ned_saturated",
    "udi",
]
