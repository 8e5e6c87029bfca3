"""``gcs key --install``: the team key sent to a real autopilot over SETUP_SIGNING, and
proven by its signed HEARTBEAT; a peer that ignores it is named."""

from __future__ import annotations

import socket
import threading

import pytest

from gcs.link import LinkError, install_signing_key
from gcs.testing import mavlink2_connection
from gcs.wire import SigningKey, mavlink

KEY = SigningKey(bytes(range(3, 35)))
VEHICLE = 9


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Autopilot(threading.Thread):
    """ArduPilot's signing as far as a GCS sees it: heartbeats at 10 Hz; SETUP_SIGNING for
    this system sets the key, after which everything it sends is signed."""

    def __init__(self, gcs_port: int, *, takes_keys: bool) -> None:
        super().__init__(daemon=True)
        # once signing, it drops the GCS's unsigned frames (robust parsing: pymavlink raised
        # on them otherwise, which ended this thread in a full test run)
        self.conn = mavlink2_connection(f"udpout:127.0.0.1:{gcs_port}", source_system=VEHICLE,
                                        source_component=1)
        self.takes_keys = takes_keys
        self.key: bytes | None = None
        self._quit = threading.Event()

    def run(self) -> None:
        while not self._quit.is_set():
            self.conn.mav.heartbeat_send(mavlink.MAV_TYPE_QUADROTOR,
                                         mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, 0)
            msg = self.conn.recv_match(type="SETUP_SIGNING", blocking=True, timeout=0.1)
            if msg is not None and msg.target_system == VEHICLE and self.takes_keys:
                self.key = bytes(msg.secret_key)
                self.conn.setup_signing(self.key, sign_outgoing=True,
                                        initial_timestamp=msg.initial_timestamp)

    def stop(self) -> None:
        self._quit.set()
        self.join(timeout=2)
        self.conn.close()


def test_the_key_is_installed_and_proven() -> None:
    port = free_udp_port()
    pilot = Autopilot(port, takes_keys=True)
    pilot.start()
    try:
        install_signing_key(f"udpin:127.0.0.1:{port}", VEHICLE, KEY, timeout_s=15.0)
        assert pilot.key == KEY.secret
    finally:
        pilot.stop()


def test_an_autopilot_that_ignores_the_key_is_named() -> None:
    port = free_udp_port()
    pilot = Autopilot(port, takes_keys=False)
    pilot.start()
    try:
        with pytest.raises(LinkError, match=f"vehicle {VEHICLE}.*did not take it"):
            install_signing_key(f"udpin:127.0.0.1:{port}", VEHICLE, KEY, timeout_s=1.5)
    finally:
        pilot.stop()


def test_no_vehicle_on_the_connection_is_named() -> None:
    with pytest.raises(LinkError, match="HEARTBEAT from vehicle 9"):
        install_signing_key(f"udpin:127.0.0.1:{free_udp_port()}", VEHICLE, KEY, timeout_s=0.5)
