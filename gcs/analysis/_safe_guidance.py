"""The guidance config the GCS flies: its scales within what the analysis certifies (the
largest inside the safe deformation, the smallest where accelerating loads no vehicle to
its reference thrust).

Why one place: the GCS caps the scale here in flight, and a scenario or a user that
asks for more is told the scale that will be flown, from the same function.
"""

from __future__ import annotations

import dataclasses

from gcs.analysis._certificate import Analysis
from gcs.config import GuidanceConfig, Team

__all__ = ["safe_guidance"]


def safe_guidance(team: Team, analysis: Analysis) -> GuidanceConfig:
    """``team``'s guidance config with ``scale_min`` and ``scale_max`` those flown."""
    guidance = team.config.guidance
    low = max(guidance.scale_min, analysis.scale_min_flown)
    high = min(guidance.scale_max, analysis.scale_max_flown)
    if (low, high) == (guidance.scale_min, guidance.scale_max):
        return guidance
    return dataclasses.replace(guidance, scale_min=low, scale_max=high)
