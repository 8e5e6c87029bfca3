"""Building a pymavlink message from a checked MAVLink 2 frame, without pymavlink's decode.

Why: the GCS decodes every telemetry frame of every vehicle (a hundred
vehicles send thousands per second), and pymavlink's generic ``decode``
re-parses the header, re-computes the checksum the
:class:`~gcs.wire.FrameDecoder` has already checked and walks the
field list in Python each time. For message types whose fields are all
scalars (no arrays, no strings; most telemetry), the payload maps straight
onto the type's ``struct`` and its constructor; the object built is the one
``decode`` builds (same fields, header, buffer, checksum and signing flags,
checked field by field in the tests). Other types return None and go
through pymavlink.
"""

from __future__ import annotations

import struct

from gcs.wire._dialect import MavMessage, mavlink

__all__ = ["HEADER_V2", "unpack_v2"]

HEADER_V2 = 10
"""Bytes before the payload in a MAVLink 2 frame (magic to message id)."""
_CRC = struct.Struct("<H")


class _Layout:
    """How one scalar-only message type's payload maps onto its constructor."""

    __slots__ = ("cls", "order", "size", "unpack")

    def __init__(self, cls: type[MavMessage]) -> None:
        self.cls = cls
        self.unpack = cls.unpacker.unpack
        self.size = cls.unpacker.size
        self.order = tuple(cls.orders)  # constructor argument i is wire field order[i]


def _layout(cls: type[MavMessage]) -> _Layout | None:
    scalar = all(n == 1 for n in cls.lengths) and not any(
        t.startswith("char") for t in cls.fieldtypes)
    return _Layout(cls) if scalar else None


_LAYOUTS: dict[int, _Layout | None] = {msgid: _layout(cls)
                                       for msgid, cls in mavlink.mavlink_map.items()}


def unpack_v2(frame: bytearray, *, msgid: int, signature_len: int) -> MavMessage | None:
    """The message in a whole, checked MAVLink 2 ``frame``; None if its type needs pymavlink.

    ``signature_len`` is 13 for a signed frame, else 0. The caller sets the
    signing flags (``_signed``, ``_link_id``) as it does after pymavlink's decode.
    """
    layout = _LAYOUTS.get(msgid)
    if layout is None:
        return None
    end = len(frame) - 2 - signature_len
    payload = bytes(frame[HEADER_V2:end])
    if len(payload) < layout.size:  # MAVLink 2 dropped trailing zeros (or extensions)
        payload += bytes(layout.size - len(payload))
    fields = layout.unpack(payload[:layout.size])
    msg = layout.cls(*[fields[i] for i in layout.order])
    msg._msgbuf = frame
    msg._payload = frame[6:end]  # as pymavlink (from byte 6, for MAVLink 1 compatibility)
    msg._crc = _CRC.unpack_from(frame, end)[0]
    msg._header = mavlink.MAVLink_header(msgid, frame[2], frame[3], frame[1], frame[4],
                                         frame[5], frame[6])
    return msg
