"""The one place that builds zenoh configurations and opens sessions.

Embedded default: peer mode on loopback with no router to install. The sim
process listens on :data:`DEFAULT_ENDPOINT`; the GCS and viewers connect to it
(a peer whose connect endpoint is not up yet keeps retrying in the
background). Multicast scouting is off by default so that unrelated processes
on the same host (or parallel tests) never find each other by accident;
every connection is explicit.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import zenoh

from gcs.common import field

__all__ = ["DEFAULT_ENDPOINT", "ZenohSettings", "open_session", "zenoh_config"]

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
"""Loopback endpoint the sim listens on and the GCS connects to by default."""

_ENDPOINT_RE = re.compile(r"[a-z][a-z0-9\-]*/\S+")


def _check_endpoints(name: str, endpoints: Sequence[str]) -> None:
    for e in endpoints:
        if not isinstance(e, str) or not _ENDPOINT_RE.fullmatch(e):
            raise ValueError(f"{name}: zenoh endpoint must look like 'tcp/127.0.0.1:7447', "
                             f"got {e!r}")


@dataclass(frozen=True)
class ZenohSettings:
    """How this process joins the zenoh fabric."""

    mode: Literal["peer", "client"] = field(
        doc="'peer' (no router needed) or 'client' (through a zenoh router)", default="peer")
    listen: tuple[str, ...] = field(
        doc="endpoints to accept connections on, e.g. tcp/127.0.0.1:7447", default=())
    connect: tuple[str, ...] = field(
        doc="endpoints to connect to (retried until they come up)",
        default=(DEFAULT_ENDPOINT,))
    multicast_scouting: bool = field(
        doc="discover peers by UDP multicast (off: only explicit endpoints)", default=False)

    def __post_init__(self) -> None:
        _check_endpoints("listen", self.listen)
        _check_endpoints("connect", self.connect)
        if self.mode == "client" and not self.connect:
            raise ValueError("connect: client mode needs at least one router endpoint")

    def to_config(self) -> zenoh.Config:
        """The zenoh configuration for these settings."""
        return zenoh_config(mode=self.mode, listen=self.listen, connect=self.connect,
                            multicast_scouting=self.multicast_scouting)


def zenoh_config(*, mode: Literal["peer", "client"] = "peer", listen: Sequence[str] = (),
                 connect: Sequence[str] = (DEFAULT_ENDPOINT,),
                 multicast_scouting: bool = False) -> zenoh.Config:
    """Build a zenoh configuration; the only function in the project that does.

    ``listen`` and ``connect`` are zenoh endpoints (``tcp/<host>:<port>``). An
    empty ``listen`` in peer mode still opens a listener on an ephemeral
    loopback port so that gossip can introduce other peers to this one.
    """
    _check_endpoints("listen", listen)
    _check_endpoints("connect", connect)
    config = zenoh.Config()
    config.insert_json5("mode", json.dumps(mode))
    if mode == "peer":
        config.insert_json5("listen/endpoints", json.dumps(list(listen) or ["tcp/127.0.0.1:0"]))
    config.insert_json5("connect/endpoints", json.dumps(list(connect)))
    config.insert_json5("scouting/multicast/enabled", json.dumps(bool(multicast_scouting)))
    return config


def open_session(settings: ZenohSettings) -> zenoh.Session:
    """Open a zenoh session; a listener that cannot bind raises RuntimeError naming it."""
    try:
        return zenoh.open(settings.to_config())
    except zenoh.ZError as exc:
        raise RuntimeError(f"cannot open zenoh session (mode {settings.mode}, listen "
                           f"{list(settings.listen)}, connect {list(settings.connect)}): "
                           f"{exc}") from None
