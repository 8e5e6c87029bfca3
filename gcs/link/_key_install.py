"""Installing the team key on a real autopilot (``gcs key --install``), as MAVProxy's
``signing setup`` does, and proving that it took.

Why: a real vehicle whose link is unsigned obeys anyone who reaches its radio.
ArduPilot (and PX4 where signing is enabled) takes its key from SETUP_SIGNING;
from then on it signs what it sends and refuses unsigned commands. The key is
sent over a link the user names, best a USB cable: SETUP_SIGNING itself is not
secret.
"""

from __future__ import annotations

import time

from gcs.link._errors import LinkError
from gcs.link._link import Link
from gcs.transport import MavutilTransport
from gcs.wire import DEFAULT_GCS_SYSTEM_ID, SigningKey, mavlink, signing_timestamp

__all__ = ["install_signing_key"]

_SENDS = 3  # SETUP_SIGNING has no ack: sent a few times, then proven by signed traffic
_ROUND_S = 2.0  # how long one round waits for a signed HEARTBEAT before sending again


def _open(connection: str, sysid: int, key: SigningKey | None, *, component_id: int,
          gcs_system_id: int) -> Link:
    try:
        transport = MavutilTransport(connection)
    except (RuntimeError, ValueError) as exc:
        raise LinkError(sysid, str(exc)) from None
    try:
        return Link(sysid, transport, gcs_system_id=gcs_system_id, target_component=component_id,
                    signing_key=key, timesync_period_s=0.0).start()
    except BaseException:
        transport.close()
        raise


def install_signing_key(connection: str, sysid: int, key: SigningKey, *, component_id: int = 1,
                        timeout_s: float = 5.0,
                        gcs_system_id: int = DEFAULT_GCS_SYSTEM_ID) -> None:
    """Send ``key`` to vehicle ``sysid`` over ``connection`` (a pymavlink connection string)
    and wait until it signs its HEARTBEAT with it; LinkError naming what failed.

    SETUP_SIGNING has no answer: it is sent again, round after round, until a signed
    HEARTBEAT proves it arrived or ``timeout_s`` has passed."""
    deadline = time.monotonic() + timeout_s
    while True:
        with _open(connection, sysid, None, component_id=component_id,
                   gcs_system_id=gcs_system_id) as plain:
            plain.wait_for(lambda tel: tel.heartbeat is not None,
                           timeout_s=max(0.1, deadline - time.monotonic()),
                           what=f"a HEARTBEAT from vehicle {sysid} on {connection}")
            for _ in range(_SENDS):
                plain.send_message(mavlink.MAVLink_setup_signing_message(
                    target_system=sysid, target_component=component_id,
                    secret_key=list(key.secret), initial_timestamp=signing_timestamp()))
                time.sleep(0.1)
        remaining = deadline - time.monotonic()
        with _open(connection, sysid, key, component_id=component_id,
                   gcs_system_id=gcs_system_id) as signed:
            try:  # a signed link hears only frames signed with the key
                signed.wait_for(lambda tel: tel.heartbeat is not None,
                                timeout_s=max(0.1, min(_ROUND_S, remaining)),
                                what="its first signed HEARTBEAT")
                return
            except LinkError:
                if remaining > _ROUND_S:
                    continue
                raise LinkError(sysid, f"sent the key, but no HEARTBEAT signed with it came "
                                       f"back within {timeout_s:g} s: the autopilot did not "
                                       f"take it (ArduPilot takes it on any link; PX4 only "
                                       f"with MAV_SIGN_CFG set, over USB)") from None
