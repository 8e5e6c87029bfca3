"""Link configuration: one :class:`LinkConfig` per vehicle, plus the GCS's own identity.

In the team configuration the vehicles' links are a list under ``links:``::

    links:
      - {sysid: 1, transport: zenoh, profile: sim}
      - {sysid: 2, transport: "udpin:0.0.0.0:14551", profile: ardupilot,
         signing_key: keys/vehicle2.key}

and :class:`GcsLinkConfig` (fleet name, GCS system id, zenoh settings) sits
beside it. Paths are relative to the configuration file's folder.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from gcs.common import ConfigError, field, from_mapping
from gcs.transport import ZenohSettings, is_connection_string
from gcs.wire import DEFAULT_GCS_COMPONENT_ID, DEFAULT_GCS_SYSTEM_ID
from gcs.wire.keys import check_fleet

__all__ = ["ZENOH", "GcsLinkConfig", "LinkConfig", "check_links", "links_from_list"]

ZENOH = "zenoh"
"""The ``transport`` value selecting the zenoh fabric (simulated vehicles)."""


@dataclass(frozen=True)
class LinkConfig:
    """How the GCS reaches one vehicle."""

    sysid: int = field(doc="the vehicle's MAVLink system id", ge=1, le=255)
    transport: str = field(
        doc="'zenoh', or a pymavlink connection string: udpin:<ip>:<port>, udpout:<ip>:<port>, "
            "tcp:<host>:<port>, tcpin:<ip>:<port>, or a serial device such as /dev/ttyACM0",
        default=ZENOH)
    profile: Literal["sim", "px4", "ardupilot"] = field(
        doc="autopilot profile: command sequences and setpoint channels", default="sim")
    signing_key: str | None = field(
        doc="MAVLink 2 signing key file (32 raw bytes or 64 hex characters), or 'team' for "
            "the team key; omitted: the team key on simulated links, none on px4 and "
            "ardupilot links (shown unsigned in red)", default=None)
    signing_link_id: int = field(doc="link id written into outgoing signatures",
                                 default=0, ge=0, le=255)
    component_id: int = field(doc="the vehicle autopilot's MAVLink component id",
                              default=1, ge=1, le=255)
    baud: int = field(doc="serial baud rate, bit/s (serial devices only)", default=57600, gt=0)
    command_timeout_s: float = field(doc="wait for each COMMAND_ACK, s", default=1.0, gt=0.0)
    command_retries: int = field(doc="re-sends of an unanswered command", default=2, ge=0)
    heartbeat_timeout_s: float = field(
        doc="HEARTBEAT age after which the vehicle counts as gone, s", default=3.0, gt=0.0)

    def __post_init__(self) -> None:
        if self.transport != ZENOH and not is_connection_string(self.transport):
            raise ValueError(
                f"transport: must be 'zenoh' or a pymavlink connection string such as "
                f"'udpin:0.0.0.0:14550', 'tcp:127.0.0.1:5760' or '/dev/ttyACM0', "
                f"got {self.transport!r}")

    def signing_key_path(self, base_dir: Path) -> Path | None:
        """The key file resolved against the configuration's folder (None: none, or the
        team key, which :func:`gcs.config.link_key` resolves)."""
        if self.signing_key is None or self.signing_key == "team":
            return None
        path = Path(self.signing_key).expanduser()
        return path if path.is_absolute() else base_dir / path


@dataclass(frozen=True)
class GcsLinkConfig:
    """The GCS's side of all links."""

    fleet: str = field(doc="fleet name in zenoh keys (fleet/<fleet>/...)", default="default")
    system_id: int = field(doc="the GCS's own MAVLink system id (not 255: MAVProxy and QGC)",
                           default=DEFAULT_GCS_SYSTEM_ID, ge=1, le=255)
    component_id: int = field(doc="the GCS's MAVLink component id",
                              default=DEFAULT_GCS_COMPONENT_ID, ge=1, le=255)
    heartbeat_period_s: float = field(doc="period of the GCS HEARTBEAT, s (0: none)",
                                      default=1.0, ge=0.0)
    timesync_period_s: float = field(doc="period of TIMESYNC round-trip probes, s (0: none)",
                                     default=1.0, ge=0.0)
    zenoh: ZenohSettings = field(doc="how to join the zenoh fabric",
                                 default_factory=ZenohSettings)
    signing: bool = field(
        doc="sign the simulated links with the team key and refuse unsigned frames; false "
            "turns it off (the page says so in red)", default=True)
    team_key: str | None = field(
        doc="the team key file; default: formation-gcs/team.key in the user's config "
            "directory, made on first use", default=None)

    def __post_init__(self) -> None:
        try:
            check_fleet(self.fleet)
        except ValueError as exc:
            raise ValueError(f"fleet: {exc}") from None
        if self.system_id == 255:
            raise ValueError("system_id: 255 is what MAVProxy and QGroundControl use, and an "
                             "autopilot could take their frames for ours; choose another "
                             f"(default {DEFAULT_GCS_SYSTEM_ID})")


def check_links(links: Sequence[LinkConfig], *, gcs_system_id: int, source: str,
                where: str = "links") -> None:
    """Refuse duplicate system ids, the GCS's own id, and two links on one port."""
    seen: dict[int, int] = {}
    ports: dict[str, int] = {}
    for i, link in enumerate(links):
        at = f"{where}[{i}]"
        if link.sysid in seen:
            raise ConfigError(source, f"{at}.sysid", f"system id {link.sysid} already used by "
                                                     f"{where}[{seen[link.sysid]}]")
        if link.sysid == gcs_system_id:
            raise ConfigError(source, f"{at}.sysid",
                              f"system id {link.sysid} is the GCS's own system id")
        if link.transport != ZENOH:
            if link.transport in ports:
                raise ConfigError(source, f"{at}.transport", f"{link.transport!r} already used "
                                  f"by {where}[{ports[link.transport]}]; one port per vehicle")
            ports[link.transport] = i
        seen[link.sysid] = i


def links_from_list(data: Any, source: str, *, gcs_system_id: int = DEFAULT_GCS_SYSTEM_ID,
                    where: str = "links") -> tuple[LinkConfig, ...]:
    """Validated link configurations from the YAML list under ``links:``."""
    if not isinstance(data, list):
        kind = "nothing (null)" if data is None else type(data).__name__
        raise ConfigError(source, where, f"expected a list of links, got {kind}")
    links = tuple(from_mapping(LinkConfig, item, source, f"{where}[{i}]")
                  for i, item in enumerate(data))
    check_links(links, gcs_system_id=gcs_system_id, source=source, where=where)
    return links
