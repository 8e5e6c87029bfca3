"""GCS link layer: every vehicle, simulated or real, is a MAVLink 2 peer.

One :class:`Link` per vehicle carries MAVLink 2 frames over a
:class:`Transport` (zenoh for the simulated vehicles, any pymavlink
connection string for real autopilots), keeps the latest telemetry and the
link health, and sends setpoints and acknowledged commands. An
:class:`AutopilotProfile` (``sim``, ``px4``, ``ardupilot``) knows each
autopilot's command sequences. :class:`LinkManager` opens all links from
configuration and reports vehicles that appear, vanish or are missing.

The layer is the GCS's alone: the wire formats it speaks (``gcs.wire``) and the
carriers it speaks over (``gcs.transport``) are what the simulated vehicles share.

Modules:

    ``_discovery``          Which vehicles are present: appear/vanish events and the
                            configured ones that are missing.
    ``_errors``             Command outcomes and the errors a link raises, each naming the
                            vehicle.
    ``_fanout``             One frame to each of many links at once: the loop's setpoints
                            for a whole fleet.
    ``_health``             Link health of one vehicle: is it alive, what is lost, what is
                            refused, how slow.
    ``_key_install``        Installing the team key on a real autopilot (SETUP_SIGNING), and
                            proving that it took.
    ``_link``               The GCS's link to one vehicle: MAVLink in and out, latest
                            telemetry, health, commands.
    ``_manager``            All of the GCS's links, opened from configuration and closed
                            together.
    ``_params``             One autopilot parameter read or set over MAVLink's parameter
                            protocol, confirmed.
    ``_profile``            Autopilot profiles: how each kind of vehicle is armed, launched,
                            switched and landed.
    ``_profile_ardupilot``  Profile of ArduCopter in GUIDED mode, with the GCS-side vertical
                            loop.
    ``_profile_px4``        Profile of PX4 in OFFBOARD mode.
    ``_profile_sim``        Profile of the simulated vehicles (this repository's onboard
                            autopilot).
    ``_profiles``           Choosing an autopilot profile by its configured name.
    ``_setpoint_stream``    A team's setpoint stream: vertical channels, packing, batching,
                            gaps and re-sends between ticks.
"""

from gcs.link._discovery import Presence, PresenceEvent
from gcs.link._errors import CommandAck, CommandError, LinkError
from gcs.link._fanout import Fanout
from gcs.link._health import LinkHealth
from gcs.link._key_install import install_signing_key
from gcs.link._link import Link, Outbound
from gcs.link._manager import LinkManager
from gcs.link._params import ParamClient, ParamValue
from gcs.link._profile import AutopilotProfile
from gcs.link._profiles import make_profile
from gcs.link._setpoint_stream import SetpointStream

__all__ = [
    "AutopilotProfile",
    "CommandAck",
    "CommandError",
    "Fanout",
    "Link",
    "LinkError",
    "LinkHealth",
    "LinkManager",
    "Outbound",
    "ParamClient",
    "ParamValue",
    "Presence",
    "PresenceEvent",
    "SetpointStream",
    "install_signing_key",
    "make_profile",
]
