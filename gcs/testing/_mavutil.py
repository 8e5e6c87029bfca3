"""The team key for tests and scripts, and a pymavlink ``mavutil`` connection signed
with it, as a user's script or MAVProxy (``signing key``) joins a signed team.

Why: every simulated vehicle refuses unsigned frames by default, so a test or a
script that talks to one over its UDP port signs the way a real ground station
does, with the key the GCS and the simulator share.
"""

from __future__ import annotations

from typing import Any

from pymavlink import mavutil
from pymavlink.dialects.v20 import common as v20

from gcs.config import default_team_key_path, ensure_team_key
from gcs.wire import SigningKey, signing_timestamp

__all__ = ["mavlink2_connection", "signed_connection", "team_key"]


def team_key() -> SigningKey:
    """This user's team key (made on first use), as the GCS and the simulator use it:
    to sign MAVLink, and to seal what a test publishes on the simulator's control key
    (``gcs.wire.Sealer(team_key(), keys.sim(fleet, "control"))``)."""
    return ensure_team_key(default_team_key_path())[0]


def mavlink2_connection(device: str, *, source_system: int, source_component: int,
                        **kwargs: Any) -> Any:
    """``mavutil.mavlink_connection(device, ...)`` that speaks MAVLink 2 from its first frame
    and parses robustly (frames it cannot check are dropped, not raised).

    Why: mavutil speaks MAVLink 1, which cannot be signed, until it has heard MAVLink 2
    (unless its process-wide dialect was switched already by an earlier connection), and
    it raises on a frame whose signature it refuses, which ends a reading thread.
    """
    conn = mavutil.mavlink_connection(device, source_system=source_system,
                                      source_component=source_component, **kwargs)
    conn.mav = v20.MAVLink(conn, srcSystem=source_system, srcComponent=source_component)
    conn.mav.robust_parsing = True
    conn.WIRE_PROTOCOL_VERSION = "2.0"
    conn.first_byte = False
    return conn


def signed_connection(device: str, *, key: SigningKey | None = None, source_system: int = 245,
                      source_component: int = 190, link_id: int = 7,
                      **kwargs: Any) -> Any:
    """``mavutil.mavlink_connection(device, ...)`` that signs everything it sends with
    ``key`` (default: this user's team key) and drops unsigned frames it receives."""
    if key is None:
        key = team_key()
    conn = mavlink2_connection(device, source_system=source_system,
                               source_component=source_component, **kwargs)
    conn.setup_signing(key.secret, sign_outgoing=True, link_id=link_id,
                       initial_timestamp=signing_timestamp())
    return conn
