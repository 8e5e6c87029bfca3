"""A team file, loaded and validated: shape, gains, limits, payload, links.

Every mistake is refused with one :class:`ConfigError` line naming the file and
the field; ``docs/teams.md`` lists the fields.

Modules:

    ``_links``  Link configuration: one :class:`LinkConfig` per vehicle, plus the GCS's own
                identity.
    ``_team``   Team configuration: the shape, gains, limits, payload and airframe of one
                team.
"""

from gcs.config._links import ZENOH, GcsLinkConfig, LinkConfig, check_links
from gcs.config._team import (
    GuidanceConfig,
    OperatorConfig,
    SafetyConfig,
    Team,
    TeamConfig,
    load_team,
)

__all__ = [
    "ZENOH",
    "GcsLinkConfig",
    "GuidanceConfig",
    "LinkConfig",
    "OperatorConfig",
    "SafetyConfig",
    "Team",
    "TeamConfig",
    "check_links",
    "load_team",
]
