"""MAVLink 2 encoding for one sender (the GCS, or one simulated vehicle).

Every frame carries the sender's own system and component id and a
per-sender sequence number; with a key, every frame is signed. The same class
serves the GCS (system id 245 by default: not 255, which MAVProxy and QGC
use) and the simulated vehicles' endpoint (their own system id, component 1).
"""

from __future__ import annotations

import functools
import re
import struct
import threading
import time
from collections.abc import Callable, Mapping

import numpy as np

from gcs.link.crc import frame_crc
from gcs.link.dialect import MavMessage, mavlink
from gcs.link.signing import SigningKey, signature, signing_timestamp

__all__ = ["DEFAULT_GCS_COMPONENT_ID", "DEFAULT_GCS_SYSTEM_ID", "MavlinkEncoder", "frame_dtype",
           "packed_frames"]

DEFAULT_GCS_SYSTEM_ID = 245
"""The GCS's own MAVLink system id unless configured otherwise."""

_HEADER = struct.Struct("<BBBBBBBHB")
_HEADER_SIZE = _HEADER.size
_CRC = struct.Struct("<H")
_SIGNATURE_STAMP = struct.Struct("<BQ")
_IFLAG_SIGNED = mavlink.MAVLINK_IFLAG_SIGNED


DEFAULT_GCS_COMPONENT_ID = mavlink.MAV_COMP_ID_MISSIONPLANNER
"""The GCS's component id (190, ``MAV_COMP_ID_MISSIONPLANNER``, a ground station)."""


@functools.cache
def _frame_struct(message_type: type[MavMessage]) -> struct.Struct:
    """Header and full payload of ``message_type`` in one struct: one pack call per frame."""
    return struct.Struct(_HEADER.format + message_type.unpacker.format.lstrip("<"))


_NUMPY_CODES = {"b": "i1", "B": "u1", "h": "<i2", "H": "<u2", "i": "<i4", "I": "<u4",
                "q": "<i8", "Q": "<u8", "f": "<f4", "d": "<f8"}


@functools.cache
def frame_dtype(message_type: type[MavMessage]) -> np.dtype:
    """numpy layout of a packed frame of ``message_type``: the header, then the payload fields.

    Header fields are ``marker``, ``length``, ``incompat``, ``compat``, ``seq``,
    ``sysid``, ``compid``, ``msgid_lo``, ``msgid_hi``; payload fields have
    their MAVLink names. Scalar fields only.
    """
    codes = re.findall(r"(\d*)([a-zA-Z])", message_type.unpacker.format.lstrip("<"))
    if any(count or code not in _NUMPY_CODES for count, code in codes):
        raise ValueError(f"{message_type.msgname}: only messages of scalar numeric fields "
                         "can be packed in bulk")
    header = [("marker", "u1"), ("length", "u1"), ("incompat", "u1"), ("compat", "u1"),
              ("seq", "u1"), ("sysid", "u1"), ("compid", "u1"), ("msgid_lo", "<u2"),
              ("msgid_hi", "u1")]
    fields = [(name, _NUMPY_CODES[code]) for name, (_count, code)
              in zip(message_type.ordered_fieldnames, codes, strict=True)]
    return np.dtype(header + fields)


def packed_frames(message_type: type[MavMessage], n: int,
                  fields: Mapping[str, np.ndarray | float]) -> list[bytes]:
    """``n`` packed frames of ``message_type`` at once, for :meth:`MavlinkEncoder.restamp`.

    ``fields``: payload field name to one value or one per frame; the others
    are zero. Why: one numpy fill for a whole fleet's setpoints costs what
    packing two of them one by one does.
    """
    rows = np.zeros(n, frame_dtype(message_type))
    rows["marker"] = mavlink.PROTOCOL_MARKER_V2
    rows["msgid_lo"] = message_type.id & 0xFFFF
    rows["msgid_hi"] = message_type.id >> 16
    for name, value in fields.items():
        rows[name] = value
    size = rows.dtype.itemsize
    data = rows.tobytes()
    return [data[k:k + size] for k in range(0, n * size, size)]


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
        msgid = message_type.id
        packed = _frame_struct(message_type).pack(mavlink.PROTOCOL_MARKER_V2, 0, 0, 0, 0, 0, 0,
                                                  msgid & 0xFFFF, msgid >> 16, *values)
        return self.restamp(packed, message_type.crc_extra)

    def restamp(self, packed: bytes, crc_extra: int) -> bytes:
        """``packed`` made this sender's next frame: numbered, checksummed, signed.

        ``packed`` is a MAVLink 2 header (marker and message id set; length,
        flags, sequence and sender ids are overwritten) and the full payload,
        without checksum, as :func:`packed_frames` builds many at once. The
        payload's trailing zeros are dropped, as MAVLink 2 requires.
        """
        if packed[-1] == 0:  # rare: most messages end in a non-zero field
            packed = packed[:_HEADER_SIZE] + (packed[_HEADER_SIZE:].rstrip(b"\0") or b"\0")
        mav = self._mav
        with self._lock:
            signed = self._signed
            frame = (packed[:1] + bytes((len(packed) - _HEADER_SIZE, _IFLAG_SIGNED if signed else 0,
                                         0, mav.seq, mav.srcSystem, mav.srcComponent))
                     + packed[7:])
            frame += _CRC.pack(frame_crc(frame[1:], crc_extra))
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
