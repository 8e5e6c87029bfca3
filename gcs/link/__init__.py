"""GCS link layer: every vehicle, simulated or real, is a MAVLink 2 peer.

One :class:`Link` per vehicle carries MAVLink 2 frames over a
:class:`Transport` (zenoh for the simulated vehicles, any pymavlink
connection string for real autopilots), keeps the latest telemetry and the
link health, and sends setpoints and acknowledged commands. An
:class:`AutopilotProfile` (``sim``, ``px4``, ``ardupilot``) knows each
autopilot's command sequences. :class:`LinkManager` opens all links from
configuration and reports vehicles that appear, vanish or are missing.

The codec pieces (:class:`MavlinkEncoder`, :class:`FrameDecoder`, signing,
:mod:`gcs.link.keys`, :class:`SimMode`, :func:`read_setpoint`,
:class:`ZenohTransport`) are shared with the simulated vehicles' endpoint.
"""

from gcs.link import keys
from gcs.link.config import ZENOH, GcsLinkConfig, LinkConfig, check_links, links_from_list
from gcs.link.decoder import DecodeStats, FrameDecoder
from gcs.link.dialect import MavMessage, command_name, mavlink, message_id, message_name
from gcs.link.discovery import Discovery, Presence, PresenceEvent, PresenceSource
from gcs.link.encoder import DEFAULT_GCS_COMPONENT_ID, DEFAULT_GCS_SYSTEM_ID, MavlinkEncoder
from gcs.link.errors import CommandAck, CommandError, CommandResult, LinkError
from gcs.link.fanout import Fanout
from gcs.link.health import LinkHealth
from gcs.link.link import DEFAULT_TELEMETRY_RATES_HZ, Link
from gcs.link.manager import LinkManager
from gcs.link.mavutil_transport import MavutilTransport
from gcs.link.modes import (
    CUSTOM_MODE_ENABLED,
    SAFETY_ARMED,
    CopterMode,
    Px4AutoSubMode,
    Px4MainMode,
    SimMode,
    px4_custom_mode,
    px4_mode_text,
)
from gcs.link.profile import AutopilotProfile, ProfileName
from gcs.link.profile_ardupilot import ArduPilotProfile, VerticalPd
from gcs.link.profile_px4 import Px4Profile
from gcs.link.profile_sim import SimProfile
from gcs.link.profiles import make_profile
from gcs.link.setpoints import (
    MASK_ACCEL,
    MASK_ACCEL_XY_POS_Z,
    SETPOINT_MESSAGE,
    AccelSetpoint,
    SetpointKind,
    SetpointPacker,
    accel_setpoint_fields,
    accel_setpoint_message,
    read_setpoint,
)
from gcs.link.signing import (
    SignatureCheck,
    SigningKey,
    load_signing_key,
    parse_signing_key,
    write_signing_key,
)
from gcs.link.telemetry import (
    Attitude,
    Heartbeat,
    Imu,
    LocalPosition,
    Severity,
    StatusText,
    SystemStatus,
    Telemetry,
)
from gcs.link.transport import FrameDirection, Transport
from gcs.link.zenoh_session import DEFAULT_ENDPOINT, ZenohSettings, open_session, zenoh_config
from gcs.link.zenoh_transport import ZenohTransport, declare_alive, watch_alive

__all__ = [
    "CUSTOM_MODE_ENABLED",
    "DEFAULT_ENDPOINT",
    "DEFAULT_GCS_COMPONENT_ID",
    "DEFAULT_GCS_SYSTEM_ID",
    "DEFAULT_TELEMETRY_RATES_HZ",
    "MASK_ACCEL",
    "MASK_ACCEL_XY_POS_Z",
    "SAFETY_ARMED",
    "SETPOINT_MESSAGE",
    "ZENOH",
    "AccelSetpoint",
    "ArduPilotProfile",
    "Attitude",
    "AutopilotProfile",
    "CommandAck",
    "CommandError",
    "CommandResult",
    "CopterMode",
    "DecodeStats",
    "Discovery",
    "Fanout",
    "FrameDecoder",
    "FrameDirection",
    "GcsLinkConfig",
    "Heartbeat",
    "Imu",
    "Link",
    "LinkConfig",
    "LinkError",
    "LinkHealth",
    "LinkManager",
    "LocalPosition",
    "MavMessage",
    "MavlinkEncoder",
    "MavutilTransport",
    "Presence",
    "PresenceEvent",
    "PresenceSource",
    "ProfileName",
    "Px4AutoSubMode",
    "Px4MainMode",
    "Px4Profile",
    "SetpointKind",
    "SetpointPacker",
    "Severity",
    "SignatureCheck",
    "SigningKey",
    "SimMode",
    "SimProfile",
    "StatusText",
    "SystemStatus",
    "Telemetry",
    "Transport",
    "VerticalPd",
    "ZenohSettings",
    "ZenohTransport",
    "accel_setpoint_fields",
    "accel_setpoint_message",
    "check_links",
    "command_name",
    "declare_alive",
    "keys",
    "links_from_list",
    "load_signing_key",
    "make_profile",
    "mavlink",
    "message_id",
    "message_name",
    "open_session",
    "parse_signing_key",
    "px4_custom_mode",
    "px4_mode_text",
    "read_setpoint",
    "watch_alive",
    "write_signing_key",
    "zenoh_config",
]
