"""One :class:`gcs.link.Link` on a UDP port and a plain socket playing its vehicle 1."""

from __future__ import annotations

import socket
import time
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.link import Link
from gcs.transport import MavutilTransport
from gcs.wire import MavlinkEncoder, MavMessage, Telemetry


@dataclass
class Rig:
    """A Link on udpin and a plain UDP socket playing vehicle 1."""

    link: Link
    sock: socket.socket
    port: int
    vehicle: MavlinkEncoder

    def send(self, *frames: bytes) -> None:
        for frame in frames:
            self.sock.sendto(frame, ("127.0.0.1", self.port))

    def encode(self, msg: MavMessage) -> bytes:
        return self.vehicle.encode(msg)

    def wait(self, predicate: object, what: str) -> Telemetry:
        return self.link.wait_for(predicate, timeout_s=3.0, what=what)  # type: ignore[arg-type]

    def until(self, condition: object, what: str, timeout_s: float = 3.0) -> None:
        deadline = time.monotonic() + timeout_s
        while not condition():  # type: ignore[operator]
            assert time.monotonic() < deadline, f"timed out waiting for {what}"
            time.sleep(0.005)


def make_rig(**link_options: object) -> Rig:
    """A started Link for vehicle 1 on a free UDP port (no heartbeat or timesync of its own
    unless ``link_options`` ask), and the vehicle's socket."""
    transport = MavutilTransport("udpin:127.0.0.1:0")
    address = transport.local_address
    assert address is not None
    options = {"gcs_heartbeat_period_s": 0.0, "timesync_period_s": 0.0, **link_options}
    link = Link(1, transport, **options).start()  # type: ignore[arg-type]
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(2.0)
    return Rig(link, sock, address[1], MavlinkEncoder(system_id=1, component_id=1))


def heartbeat(rig: Rig, *, armed: bool = False, custom_mode: int = 3) -> bytes:
    """A quadrotor's HEARTBEAT from the rig's vehicle, custom mode ``custom_mode``."""
    base = v20.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (v20.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0)
    return rig.encode(rig.vehicle.mav.heartbeat_encode(
        v20.MAV_TYPE_QUADROTOR, v20.MAV_AUTOPILOT_GENERIC, base, custom_mode,
        v20.MAV_STATE_ACTIVE))
