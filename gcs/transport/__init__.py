"""Carriers of MAVLink frames: zenoh and anything pymavlink can open.

A :class:`Transport` moves whole frames; :class:`ZenohTransport` (with the
liveliness tokens that say a vehicle is there) serves the simulated team, and
:class:`MavutilTransport` serves real autopilots over UDP, TCP or serial.

Modules:

    ``_acl``                What each role of a team may do on zenoh, as zenoh's access control
                            by certificate.
    ``_arrivals``           Counts what arrived per source, so a receiver can wait for what
                            a sender says it sent.
    ``_certs``              A team's certificates: one CA and a certificate per role (``gcs
                            certs``).
    ``_mavutil_transport``  MAVLink frames over anything ``pymavlink.mavutil`` can open:
                            UDP, TCP, serial.
    ``_protocol``           What a link needs from a byte carrier (zenoh, UDP, TCP, serial).
    ``_tls``                This process's TLS material for zenoh: which files, checked before
                            zenoh reads them.
    ``_zenoh_session``      The one place that builds zenoh configurations and opens
                            sessions.
    ``_zenoh_transport``    MAVLink frames over zenoh, and vehicle liveliness tokens.
"""

from gcs.transport._acl import RIGHTS, ROLES, Role, RoleRights, access_control
from gcs.transport._arrivals import Arrivals
from gcs.transport._certs import certificate_files, make_team_certificates
from gcs.transport._mavutil_transport import MavutilTransport, is_connection_string
from gcs.transport._protocol import FrameDirection, Transport
from gcs.transport._tls import TlsFiles, TlsSettings, check_tls
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
    "RIGHTS",
    "ROLES",
    "Arrivals",
    "FleetReceiver",
    "FrameDirection",
    "MavutilTransport",
    "Role",
    "RoleRights",
    "TlsFiles",
    "TlsSettings",
    "Transport",
    "ZenohSettings",
    "ZenohTransport",
    "access_control",
    "bounded_payload",
    "certificate_files",
    "check_tls",
    "declare_alive",
    "is_connection_string",
    "make_team_certificates",
    "open_session",
    "watch_alive",
]
