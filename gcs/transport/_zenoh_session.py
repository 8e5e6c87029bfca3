"""The one place that builds zenoh configurations and opens sessions.

Embedded default: peer mode on loopback with no router to install. The sim
process listens on :data:`DEFAULT_ENDPOINT`; the GCS and viewers connect to it
(a peer whose connect endpoint is not up yet keeps retrying in the
background). Multicast scouting is off by default so that unrelated processes
on the same host (or parallel tests) never find each other by accident;
every connection is explicit.

With ``tls`` set (:class:`~gcs.transport._tls.TlsSettings`), every link is
TLS with mutual authentication against the team's CA, and each peer is held
to its certificate's role by zenoh's access control
(:mod:`gcs.transport._acl`): ``tcp/`` endpoints become ``tls/`` ones, so a
process never listens in the clear beside its TLS port.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

import zenoh

from gcs.common import field
from gcs.transport._tls import TlsSettings, tls_sections

__all__ = ["DEFAULT_ENDPOINT", "ZenohSettings", "open_session", "zenoh_config"]

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
"""Loopback endpoint the sim listens on and the GCS connects to by default."""

_ENDPOINT_RE = re.compile(r"[a-z][a-z0-9\-]*/\S+")

_TLS = "tls/"
"""The endpoints that authenticate with the TLS material; with TLS on, ``tcp/`` becomes
``tls/`` and anything else (udp, ws, unix sockets) is refused, as it would bypass the
certificates."""


def _check_endpoints(name: str, endpoints: Sequence[str]) -> None:
    for e in endpoints:
        if not isinstance(e, str) or not _ENDPOINT_RE.fullmatch(e):
            raise ValueError(f"{name}: zenoh endpoint must look like 'tcp/127.0.0.1:7447', "
                             f"got {e!r}")


def _secured(name: str, endpoints: Sequence[str]) -> tuple[str, ...]:
    """``endpoints`` with ``tcp/`` turned into ``tls/``; other clear protocols refused."""
    out = []
    for e in endpoints:
        e = "tls/" + e[len("tcp/"):] if e.startswith("tcp/") else e
        if not e.startswith(_TLS):
            raise ValueError(f"{name}: with tls, endpoints must be tls/ (or tcp/, made tls/), "
                             f"got {e!r}")
        out.append(e)
    return tuple(out)


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
    tls: TlsSettings | None = field(
        doc="TLS with mutual authentication and access control by role (certificates made "
            "by `gcs certs`); tcp/ endpoints become tls/", default=None)

    def __post_init__(self) -> None:
        _check_endpoints("listen", self.listen)
        _check_endpoints("connect", self.connect)
        if self.mode == "client" and not self.connect:
            raise ValueError("connect: client mode needs at least one router endpoint")
        if self.tls is not None:
            object.__setattr__(self, "listen", _secured("listen", self.listen))
            object.__setattr__(self, "connect", _secured("connect", self.connect))

    def resolved(self, base_dir: str | Path) -> ZenohSettings:
        """The same settings with relative TLS paths taken from ``base_dir`` (a team file's
        folder)."""
        return self if self.tls is None else replace(self, tls=self.tls.resolved(base_dir))

    def to_config(self) -> zenoh.Config:
        """The zenoh configuration for these settings (TLS files checked: ConfigError)."""
        return zenoh_config(mode=self.mode, listen=self.listen, connect=self.connect,
                            multicast_scouting=self.multicast_scouting, tls=self.tls)


def zenoh_config(*, mode: Literal["peer", "client"] = "peer", listen: Sequence[str] = (),
                 connect: Sequence[str] = (DEFAULT_ENDPOINT,),
                 multicast_scouting: bool = False,
                 tls: TlsSettings | None = None) -> zenoh.Config:
    """Build a zenoh configuration; the only function in the project that does.

    ``listen`` and ``connect`` are zenoh endpoints (``tcp/<host>:<port>``). An
    empty ``listen`` in peer mode still opens a listener on an ephemeral
    loopback port so that gossip can introduce other peers to this one. With
    ``tls``, endpoints are made TLS ones and its files are checked (a
    :class:`~gcs.common.ConfigError` naming the file otherwise).
    """
    _check_endpoints("listen", listen)
    _check_endpoints("connect", connect)
    local = "tcp/127.0.0.1:0"
    sections: dict[str, Any] = {}
    if tls is not None:
        listen, connect = _secured("listen", listen), _secured("connect", connect)
        local = "tls/127.0.0.1:0"
        sections = tls_sections(tls)
    config = zenoh.Config()
    config.insert_json5("mode", json.dumps(mode))
    if mode == "peer":
        config.insert_json5("listen/endpoints", json.dumps(list(listen) or [local]))
    config.insert_json5("connect/endpoints", json.dumps(list(connect)))
    config.insert_json5("scouting/multicast/enabled", json.dumps(bool(multicast_scouting)))
    for path, value in sections.items():
        config.insert_json5(path, json.dumps(value))
    return config


def open_session(settings: ZenohSettings) -> zenoh.Session:
    """Open a zenoh session; a listener that cannot bind raises RuntimeError naming it, TLS
    files that cannot be used a ConfigError naming the file."""
    config = settings.to_config()
    try:
        return zenoh.open(config)
    except zenoh.ZError as exc:
        said = " ".join(str(exc).split())  # one line
        raise RuntimeError(f"cannot open zenoh session (mode {settings.mode}, listen "
                           f"{list(settings.listen)}, connect {list(settings.connect)}): "
                           f"{said}") from None
