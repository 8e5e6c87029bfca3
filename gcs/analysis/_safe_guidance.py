"""The guidance config the GCS flies: its largest scale capped at what the analysis'
safe deformation allows.

Why one place: the GCS caps the scale here in flight, and a scenario or a user that
asks for more is told the scale that will be flown, from the same function.
"""

from __future__ import annotations

import dataclasses

from gcs.analysis._worst_case import Analysis, flown_scale_max
from gcs.config import GuidanceConfig, Team

__all__ = ["safe_guidance"]


def safe_guidance(team: Team, analysis: Analysis) -> GuidanceConfig:
    """``team``'s guidance config with ``scale_max`` capped at the safe deformation."""
    guidance = team.config.guidance
    cap = flown_scale_max(team, analysis.safe_span)
    return guidance if cap >= guidance.scale_max else dataclasses.replace(guidance,
                                                                          scale_max=cap)
