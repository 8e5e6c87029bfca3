"""Tools for integration tests of the GCS: other hosts, lossy links, raw MAVLink frames.

Modules:

    ``_frames``  MAVLink 2 frames around any payload, and where each field of a message
                 sits in it.
    ``_netns``  A second host on this machine: a network namespace joined to this one by a
                veth pair.
    ``_relay``  A TCP relay that delays and stalls a stream as a lossy radio link would.
"""

from gcs.testing._frames import field_layout, raw_frame
from gcs.testing._netns import Host, NetnsUnavailableError
from gcs.testing._relay import RTO_S, LossyRelay

__all__ = [
    "RTO_S",
    "Host",
    "LossyRelay",
    "NetnsUnavailableError",
    "field_layout",
    "raw_frame",
]
