"""Choosing an autopilot profile by its configured name."""

from __future__ import annotations

from gcs.link._link import Link
from gcs.link._profile import AutopilotProfile, ProfileName
from gcs.link._profile_ardupilot import ArduPilotProfile
from gcs.link._profile_px4 import Px4Profile
from gcs.link._profile_sim import SimProfile

__all__ = ["make_profile"]


def make_profile(name: ProfileName | str, link: Link) -> AutopilotProfile:
    """Profile ``name`` (``"sim"``, ``"px4"``, ``"ardupilot"``) bound to ``link``, defaults."""
    kind = ProfileName(name)
    if kind is ProfileName.PX4:
        return Px4Profile(link)
    if kind is ProfileName.ARDUPILOT:
        return ArduPilotProfile(link)
    return SimProfile(link)
