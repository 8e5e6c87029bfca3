"""MAVLink 2 encoding for one sender (the GCS, or one simulated vehicle).

Every frame carries the sender's own system and component id and a
per-sender sequence number; with a key, every frame is signed. The same class
serves the GCS (system id 245 by default: not 255, which MAVProxy and QGC
use) and the simulated vehicles' endpoint (their own system id, component 1).
"""

from __future__ import annotations

import struct
import threading
import time
from collections.abc import Callable

from gcs.link.crc import frame_crc
from gcs.link.dialect import MavMessage, mavlink
from gcs.link.signing import SigningKey, signature, signing_timestamp

__all__ = ["DEFAULT_GCS_COMPONENT_ID", "DEFAULT_GCS_SYSTEM_ID", "MavlinkEncoder"]

DEFAULT_GCS_SYSTEM_ID = 245
"""The GCS's own MAVLink system id unless configured otherwise."""

_HEADER = struct.Struct("<BBBBBBBHB")
_CRC = struct.Struct("<H")
_SIGNATURE_STAMP = struct.Struct("<BQ")
_IFLAG_SIGNED = mavlink.MAVLINK_IFLAG_SIGNED


DEFAULT_GCS_COMPONENT_ID = mavlink.MAV_COMP_ID_MISSIONPLANNER
"""The GCS's component id (190, ``MAV_COMP_ID_MISSIONPLANNER``, a ground station)."""


def _check_id(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 255:
        raise ValueError(f"{name} must be an integer 1..255, got {value!r}")
    return value


class MavlinkEncoder:
    """Packs messages into MAVLink 2 frames; thread-safe.

    Build messages with the factory methods of :attr:`mav` (``*_encode``,
    never ``*_send``), then turn them into bytes with :meth:`encode`.
    """

    def __init__(self, *, system_id: int, component_id: int,
                 signing_key: SigningKey | None = None, link_id: int = 0,
                 wall_clock: Callable[[], float] = time.time) -> None:
        if isinstance(link_id, bool) or not isinstance(link_id, int) or not 0 <= link_id <= 255:
            raise ValueError(f"signing link id must be an integer 0..255, got {link_id!r}")
        self._mav = mavlink.MAVLink(None, _check_id("system id", system_id),
                                    _check_id("component id", component_id))
        self._signed = signing_key is not None
        if signing_key is not None:
            self._mav.signing.secret_key = signing_key.secret
            self._mav.signing.link_id = link_id
            self._mav.signing.sign_outgoing = True
        self._wall_clock = wall_clock
        self._lock = threading.Lock()
        self.frames_sent = 0
        """Frames encoded so far."""

    @property
    def mav(self) -> mavlink.MAVLink:
        """pymavlink message factory (``mav.heartbeat_encode(...)`` and friends)."""
        return self._mav

    @property
    def system_id(self) -> int:
        """Sender system id written into every frame."""
        return self._mav.srcSystem

    @property
    def component_id(self) -> int:
        """Sender component id written into every frame."""
        return self._mav.srcComponent

    @property
    def signed(self) -> bool:
        """True if every frame is signed."""
        return self._signed

    def encode_fields(self, message_type: type[MavMessage], *values: float) -> bytes:
        """The frame :meth:`encode` gives for ``message_type(*values)``, without the object.

        ``values`` in wire order (``message_type.ordered_fieldnames``); numeric
        fields only. Why: building a pymavlink message costs several times the
        bytes it yields, and the loop sends one setpoint per vehicle per tick.
        """
        payload = message_type.unpacker.pack(*values)
        payload = payload.rstrip(b"\0") or payload[:1]  # MAVLink 2 drops trailing zeros
        msgid = message_type.id
        mav = self._mav
        with self._lock:
            signed = self._signed
            head = _HEADER.pack(mavlink.PROTOCOL_MARKER_V2, len(payload),
                                _IFLAG_SIGNED if signed else 0, 0, mav.seq, mav.srcSystem,
                                mav.srcComponent, msgid & 0xFFFF, msgid >> 16)
            frame = head + payload
            frame += _CRC.pack(frame_crc(frame[1:], message_type.crc_extra))
            if signed:
                signing = mav.signing
                signing.timestamp = max(signing.timestamp,
                                        signing_timestamp(self._wall_clock()))
                frame += _SIGNATURE_STAMP.pack(signing.link_id, signing.timestamp)[:7]
                frame += signature(signing.secret_key, frame)
                signing.timestamp += 1
            mav.seq = (mav.seq + 1) & 0xFF
            self.frames_sent += 1
        return frame

    def encode(self, msg: MavMessage) -> bytes:
        """One MAVLink 2 frame for ``msg`` with the next sequence number (and a signature)."""
        mav = self._mav
        with self._lock:
            if self._signed:
                # Signing timestamps must follow wall time and strictly increase.
                mav.signing.timestamp = max(mav.signing.timestamp,
                                            signing_timestamp(self._wall_clock()))
            frame = msg.pack(mav)
            mav.seq = (mav.seq + 1) & 0xFF
            self.frames_sent += 1
        return frame
