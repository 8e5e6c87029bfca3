"""A team file, loaded and validated: shape, gains, limits, payload, links.

Every mistake is refused with one :class:`ConfigError` line naming the file and
the field; ``docs/teams.md`` lists the fields.

Modules:

    ``_frame``  How the GCS places every vehicle in one frame: the ``team_frame:``
                section.
    ``_links``  Link configuration: one :class:`LinkConfig` per vehicle, plus the GCS's own
                identity.
    ``_team_key``  The team key: one signing key per user, made on first use.
    ``_team``   Team configuration: the shape, gains, limits, payload and airframe of one
                team.
"""

from gcs.config._frame import GeoPoint, TeamFrameConfig
from gcs.config._links import ZENOH, GcsLinkConfig, LinkConfig, check_links
from gcs.config._team import (
    GuidanceConfig,
    OperatorConfig,
    SafetyConfig,
    Team,
    TeamConfig,
    load_team,
)
from gcs.config._team_key import (
    TEAM_KEY,
    default_team_key_path,
    ensure_team_key,
    key_fingerprint,
    key_from_passphrase,
    link_key,
    seal_key,
    signing_line,
    team_key_path,
)

__all__ = [
    "TEAM_KEY",
    "ZENOH",
    "GcsLinkConfig",
    "GeoPoint",
    "GuidanceConfig",
    "LinkConfig",
    "OperatorConfig",
    "SafetyConfig",
    "Team",
    "TeamConfig",
    "TeamFrameConfig",
    "check_links",
    "default_team_key_path",
    "ensure_team_key",
    "key_fingerprint",
    "key_from_passphrase",
    "link_key",
    "load_team",
    "seal_key",
    "signing_line",
    "team_key_path",
]
