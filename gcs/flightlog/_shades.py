"""The phases' colours on a time axis, shared by the report's figures and the exported
replay's timeline (no plotting library needed to read them)."""

from __future__ import annotations

from gcs.loop import Phase

__all__ = ["PHASE_SHADES"]

PHASE_SHADES = {Phase.LIFTING.text: "#fde9b8", Phase.FORMATION.text: "#d5ecd4",
                Phase.SETTING_DOWN.text: "#d6e4f5", Phase.ABORTING.text: "#f8cfcf"}
"""Background of the time plots during the phases that carry the payload (and abort)."""
