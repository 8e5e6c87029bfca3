"""Options of one sim host run (the ``python -m sim`` flags, as a typed value).

Why: tests and scripts start hosts with exactly the options the command line
offers, and the host never reads ``sys.argv`` itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gcs.transport import DEFAULT_ENDPOINT, TlsSettings, ZenohSettings
from gcs.wire.keys import check_fleet
from sim._udp import DEFAULT_BASE_PORT, DEFAULT_GCS_PORT

__all__ = ["HostOptions"]


@dataclass(frozen=True)
class HostOptions:
    """How the sim host runs."""

    speed: float | None = 1.0
    """Sim seconds per wall second; None: as fast as possible."""
    lockstep: bool = False
    """Never run more than one guidance period past the last clock ack."""
    listen: tuple[str, ...] = (DEFAULT_ENDPOINT,)
    """Zenoh endpoints to listen on (the GCS connects here)."""
    connect: tuple[str, ...] = ()
    """Zenoh endpoints to connect to."""
    udp: bool = False
    """Also open a plain MAVLink UDP port per vehicle."""
    udp_base_port: int = DEFAULT_BASE_PORT
    """UDP port of the team's first vehicle; the one at 0-based team position k uses
    base + k (the first on base itself)."""
    udp_gcs_port: int | None = DEFAULT_GCS_PORT
    """Ground-station port on 127.0.0.1 every vehicle sends to; None: only answer peers."""
    seed: int = 0
    """Seed of all sensor noise and gusts."""
    duration: float | None = None
    """Stop after this much sim time, s; None: run until stopped."""
    fleet: str | None = None
    """Fleet name in the zenoh keys; None: the team file's ``gcs.loop._fleet``."""
    signing: bool = True
    """Sign every vehicle with the team key (or its link's key); False: ``--insecure``."""
    separate_origins: bool = False
    """Give each vehicle its own local origin at its start position, as a GPS autopilot sets
    its EKF origin at its first fix (``--separate-origins``); False: one origin, the world's,
    so every LOCAL_POSITION_NED is in one frame."""
    background: bool = False
    """Paced runs: step at background CPU priority while keeping up (:mod:`sim._priority`)."""
    tls: str | None = None
    """Folder of the team's certificates (``gcs certs``): zenoh over TLS with mutual
    authentication as the ``sim`` role, peers held to theirs; None: plain TCP."""

    def __post_init__(self) -> None:
        if self.speed is not None and not (math.isfinite(self.speed) and self.speed > 0):
            raise ValueError(f"speed must be a positive number or max, got {self.speed}")
        if self.duration is not None and not (math.isfinite(self.duration)
                                              and self.duration > 0):
            raise ValueError(f"duration must be a positive number of seconds, "
                             f"got {self.duration}")
        if not 1 <= self.udp_base_port <= 65535:
            raise ValueError(f"UDP base port must be 1..65535, got {self.udp_base_port}")
        if self.udp_gcs_port is not None and not 1 <= self.udp_gcs_port <= 65535:
            raise ValueError(f"UDP GCS port must be 1..65535, got {self.udp_gcs_port}")
        if self.fleet is not None:
            check_fleet(self.fleet)
        self.zenoh_settings()  # endpoint syntax, checked now rather than at start

    def zenoh_settings(self) -> ZenohSettings:
        """Peer mode with these endpoints, multicast scouting off."""
        tls = None if self.tls is None else TlsSettings(dir=self.tls, role="sim")
        return ZenohSettings(mode="peer", listen=self.listen, connect=self.connect, tls=tls)
