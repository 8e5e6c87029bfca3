"""A team file, loaded and validated: shape, gains, limits, payload, links.

Every mistake is refused with one :class:`ConfigError` line naming the file and
the field; ``docs/teams.md`` lists the fields.

Modules:

    ``_links``  Link configuration: one :class:`LinkConfig` per vehicle, plus the GCS's own
                identity.
    ``_team``   Team configuration: the shape, gains, limits, payload and airframe of one
                team.
"""

from gcs.config._links import ZENOH, GcsLinkConfig, LinkConfig, check_links, links_from_list
from gcs.config._team import (
    AnalysisConfig,
    ConfigError,
    EdgeSpec,
    FlightConfig,
    GuidanceConfig,
    LimitsConfig,
    OperatorConfig,
    PayloadConfig,
    SafetyConfig,
    Team,
    TeamConfig,
    VehicleSpec,
    load_team,
)

__all__ = [
    "ZENOH",
    "AnalysisConfig",
    "ConfigError",
    "EdgeSpec",
    "FlightConfig",
    "GcsLinkConfig",
    "GuidanceConfig",
    "LimitsConfig",
    "LinkConfig",
    "OperatorConfig",
    "PayloadConfig",
    "SafetyConfig",
    "Team",
    "TeamConfig",
    "VehicleSpec",
    "check_links",
    "links_from_list",
    "load_team",
]
