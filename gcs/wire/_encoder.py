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
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from gcs.wire._crc import frame_crc
from gcs.wire._dialect import MavMessage, mavlink
from gcs.wire._signing import SigningKey, signature, signing_timestamp
from gcs.wire._stamp import stamp_frames

__all__ = ["DEFAULT_GCS_COMPONENT_ID", "DEFAULT_GCS_SYSTEM_ID", "EncoderBatch", "MavlinkEncoder",
           "distinct_rows", "frame_dtype", "packed_rows"]

DEFAULT_GCS_SYSTEM_ID = 245
"""The GCS's own MAVLink system id unless configured otherwise."""

_HEADER = struct.Struct("<BBBBBBBHB")
_HEADER_SIZE = _HEADER.size
_CRC = struct.Struct("<H")
_SIGNATURE_STAMP = struct.Struct("<BQ")
_SIGNATURE_SIZE = 13  # link id, 6-byte timestamp, 6-byte signature
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


def packed_rows(message_type: type[MavMessage], n: int,
                fields: Mapping[str, np.ndarray | float]) -> np.ndarray:
    """``n`` packed frames of ``message_type`` at once, as an (n, size) uint8 array.

    ``fields``: payload field name to one value or one per frame; the others
    are zero. Why: one numpy fill for a whole fleet's setpoints costs what
    packing two of them one by one does. Finish them with
    :meth:`EncoderBatch.stamp` (or :meth:`MavlinkEncoder.restamp` row by row).
    """
    # type[Any] (pymavlink is untyped) is not Hashable to mypy: python/mypy#11470
    rows = np.zeros(n, frame_dtype(message_type))  # type: ignore[arg-type]
    rows["marker"] = mavlink.PROTOCOL_MARKER_V2
    rows["msgid_lo"] = message_type.id & 0xFFFF
    rows["msgid_hi"] = message_type.id >> 16
    for name, value in fields.items():
        rows[name] = value
    return rows.view(np.uint8).reshape(n, rows.dtype.itemsize)


def distinct_rows(rows: Sequence[int], n: int) -> np.ndarray:
    """``rows`` as an int64 array, if they are distinct and in ``0..n - 1``; else ValueError."""
    which = np.asarray(rows, np.int64).reshape(-1)
    if len(which) and not (which.min() >= 0 and which.max() < n
                           and len(np.unique(which)) == len(which)):
        raise ValueError(f"rows must be distinct, in 0..{n - 1}: {which.tolist()}")
    return which


def _check_id(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 255:
        raise ValueError(f"{name} must be an integer 1..255, got {value!r}")
    return value


class _Counters:
    """The sequence number and frame count of some encoders, one row (seq, sent) each.

    Why a shared table: an :class:`EncoderBatch` numbers a whole fleet's frames in
    one compiled pass, which reads and advances every encoder's counters at once
    (two Python attribute updates per vehicle cost more than the pass itself).
    An encoder's counters live in the table of the last batch that took it;
    ``current`` turns False when some encoder leaves, and the batch takes its
    encoders back before it numbers again.
    """

    __slots__ = ("current", "table")

    def __init__(self, rows: int) -> None:
        self.table = np.zeros((rows, 2), np.int64)
        self.current = True


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
        # (table, row) of this encoder's counters, replaced as one attribute when a batch
        # takes them, so no reader ever pairs one table with another's row
        self._slot: tuple[_Counters, int] = (_Counters(1), 0)

    def move_counters(self, counters: _Counters, row: int) -> None:
        """Hand this encoder's counters over to row ``row`` of ``counters`` (a batch's),
        under its lock so no frame is numbered meanwhile; the table they leave is no longer
        current (its batch takes its encoders back before it numbers again)."""
        with self._lock:
            old, old_row = self._slot
            counters.table[row] = old.table[old_row]
            old.current = False
            self._slot = (counters, row)

    def _counter_row(self) -> np.ndarray:
        counters, row = self._slot
        return counters.table[row]

    @property
    def seq(self) -> int:
        """Sequence number of the next frame (0..255)."""
        return int(self._counter_row()[0])

    @seq.setter
    def seq(self, value: int) -> None:
        with self._lock:
            self._counter_row()[0] = value & 0xFF

    @property
    def frames_sent(self) -> int:
        """Frames encoded so far."""
        return int(self._counter_row()[1])

    def _advance(self) -> None:
        counters = self._counter_row()
        counters[0] = (counters[0] + 1) & 0xFF
        counters[1] += 1

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
        # type[Any] (pymavlink is untyped) is not Hashable to mypy: python/mypy#11470
        layout = _frame_struct(message_type)  # type: ignore[arg-type]
        packed = layout.pack(mavlink.PROTOCOL_MARKER_V2, 0, 0, 0, 0, 0, 0,
                             msgid & 0xFFFF, msgid >> 16, *values)
        return self.restamp(packed, message_type.crc_extra)

    def restamp(self, packed: bytes, crc_extra: int) -> bytes:
        """``packed`` made this sender's next frame: numbered, checksummed, signed.

        ``packed`` is a MAVLink 2 header (marker and message id set; length,
        flags, sequence and sender ids are overwritten) and the full payload,
        without checksum, as a row of :func:`packed_rows` holds it. The
        payload's trailing zeros are dropped, as MAVLink 2 requires.
        """
        if packed[-1] == 0:  # rare: most messages end in a non-zero field
            packed = packed[:_HEADER_SIZE] + (packed[_HEADER_SIZE:].rstrip(b"\0") or b"\0")
        mav = self._mav
        with self._lock:
            signed = self._signed
            frame = (packed[:1] + bytes((len(packed) - _HEADER_SIZE, _IFLAG_SIGNED if signed else 0,
                                         0, self.seq, mav.srcSystem, mav.srcComponent))
                     + packed[7:])
            frame += _CRC.pack(frame_crc(frame[1:], crc_extra))
            if signed:
                signing = mav.signing
                signing.timestamp = max(signing.timestamp,
                                        signing_timestamp(self._wall_clock()))
                frame += _SIGNATURE_STAMP.pack(signing.link_id, signing.timestamp)[:7]
                frame += signature(signing.secret_key, frame)
                signing.timestamp += 1
            self._advance()
        return frame

    def encode(self, msg: MavMessage) -> bytes:
        """One MAVLink 2 frame for ``msg`` with the next sequence number (and a signature)."""
        mav = self._mav
        with self._lock:
            if self._signed:
                # Signing timestamps must follow wall time and strictly increase.
                mav.signing.timestamp = max(mav.signing.timestamp,
                                            signing_timestamp(self._wall_clock()))
            mav.seq = self.seq  # pymavlink numbers the frame from it
            frame = msg.pack(mav)
            self._advance()
        return frame


class EncoderBatch:
    """Encoders that each send one frame at the same moment: a fleet's setpoints.

    :meth:`stamp` gives every encoder its next frame from one row of packed
    frames, as :meth:`MavlinkEncoder.restamp` does, in one compiled pass
    (:func:`gcs.wire._stamp.stamp_frames`) for the unsigned ones. Not locked:
    the caller serializes each encoder's frames, and the batch's construction,
    with them (:class:`gcs.link.Link`'s send lock), since a numbered frame must
    leave before the next is numbered.
    """

    def __init__(self, encoders: Sequence[MavlinkEncoder]) -> None:
        self._encoders = tuple(encoders)
        if len({id(e) for e in self._encoders}) != len(self._encoders):
            raise ValueError("an encoder appears twice in the batch")
        mavs = [e.mav for e in self._encoders]
        self._sysid = np.array([m.srcSystem for m in mavs], np.uint8)
        self._compid = np.array([m.srcComponent for m in mavs], np.uint8)
        self._signed = np.array([e.signed for e in self._encoders], np.bool_)
        self._any_signed = bool(self._signed.any())
        self._all = np.arange(len(self._encoders), dtype=np.int64)
        self._counters = self._take()

    def _take(self) -> _Counters:
        """Move every encoder's counters into a new table of this batch (see :class:`_Counters`),
        each under its encoder's lock so no frame is numbered meanwhile."""
        counters = _Counters(len(self._encoders))
        for i, e in enumerate(self._encoders):
            e.move_counters(counters, i)
        return counters

    def encoder(self, i: int) -> MavlinkEncoder:
        """The encoder of row ``i``."""
        return self._encoders[i]

    def load_kernel(self) -> None:
        """Compile or load the stamping kernel now (slow the first time), so the first
        :meth:`stamp` does not wait for it."""
        packed = np.zeros((1, _HEADER_SIZE + 1), np.uint8)
        one = np.zeros(1, np.uint8)
        stamp_frames(packed, np.zeros(1, np.int64), np.zeros((1, 2), np.int64), one, one,
                     np.zeros(1, np.bool_), 0, np.empty((1, _HEADER_SIZE + 3), np.uint8))

    def stamp(self, packed: np.ndarray, crc_extra: int) -> list[bytes]:
        """Row ``i`` of ``packed`` (:func:`packed_rows`) as encoder ``i``'s next frame."""
        data, width, lengths = self.stamp_buffer(packed, crc_extra)
        return [data[k * width:k * width + size] for k, size in enumerate(lengths)]

    def stamp_buffer(self, packed: np.ndarray, crc_extra: int,
                     rows: Sequence[int] | None = None) -> tuple[bytes, int, list[int]]:
        """:meth:`stamp` as one buffer: frame ``k`` is ``data[k * width:][:lengths[k]]``.

        ``rows``: the encoders (distinct, in range) that row ``k`` of ``packed``
        goes to (default: all, in order). Why one buffer: the caller slices each
        frame as it sends it, one loop over the fleet.
        """
        # the kernel does not check bounds: a wrong row would write another's counters
        which = self._all if rows is None else distinct_rows(rows, len(self._encoders))
        if packed.shape[0] != len(which):
            raise ValueError(f"{packed.shape[0]} packed frames for {len(which)} encoders")
        if not self._counters.current:  # another batch took some encoder meanwhile
            self._counters = self._take()
        # room for a signature where some encoder signs: its frame is put in its row below
        width = packed.shape[1] + 2 + (_SIGNATURE_SIZE if self._any_signed else 0)
        out = np.empty((len(which), width), np.uint8)
        lengths = stamp_frames(packed, which, self._counters.table, self._sysid, self._compid,
                               self._signed, crc_extra, out).tolist()
        if self._any_signed:  # numbered and signed one by one by restamp
            for k in np.flatnonzero(self._signed[which]).tolist():
                frame = self._encoders[which[k]].restamp(packed[k].tobytes(), crc_extra)
                out[k, :len(frame)] = np.frombuffer(frame, np.uint8)
                lengths[k] = len(frame)
        return out.tobytes(), width, lengths
