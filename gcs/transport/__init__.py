"""Carriers of MAVLink frames: zenoh and anything pymavlink can open.

A :class:`Transport` moves whole frames; :class:`ZenohTransport` (with the
liveliness tokens that say a vehicle is there) serves the simulated team, and
:class:`MavutilTransport` serves real autopilots over UDP, TCP or serial.

Modules:

    ``_arrivals``           Counts what arrived per source, so a receiver can wait for what
                            a sender says it sent.
    ``_mavutil_transport``  MAVLink frames over anything ``pymavlink.mavutil`` can open:
                            UDP, TCP, serial.
    ``_protocol``           What a link needs from a byte carrier (zenoh, UDP, TCP, serial).
    ``_zenoh_session``      The one place that builds zenoh configurations and opens
                            sessions.
    ``_zenoh_transport``    MAVLink frames over zenoh, and vehicle liveliness tokens.
"""

from gcs.transport._arrivals import Arrivals
from gcs.transport._mavutil_transport import MavutilTransport, is_connection_string
from gcs.transport._protocol import FrameDirection, Transport
from gcs.transport._zenoh_session import DEFAULT_ENDPOINT, ZenohSettings, open_session
from gcs.transport._zenoh_transport import (
    MAVLINK_PAYLOAD_MAX,
    FleetReceiver,
    ZenohTransport,
    bounded_payload,
    declare_alive,
    watch_alive,
)

__all__ = [
    "DEFAULT_ENDPOINT",
    "MAVLINK_PAYLOAD_MAX",
    "Arrivals",
    "FleetReceiver",
    "FrameDirection",
    "MavutilTransport",
    "Transport",
    "ZenohSettings",
    "ZenohTransport",
    "bounded_payload",
    "declare_alive",
    "is_connection_string",
    "open_session",
    "watch_alive",
]
