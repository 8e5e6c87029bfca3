"""MAVLink 2 frames around any payload, and where each field of a message sits in it.

Why: a fuzz test or a hostile peer needs frames whose checksum holds around
payloads no encoder would write (wrong lengths, NaN, any bytes), so that the
decoder's checks past the checksum are what gets tested.
"""

from __future__ import annotations

import struct

from gcs.wire import frame_crc, mavlink

__all__ = ["field_layout", "raw_frame"]


def raw_frame(msgid: int, payload: bytes, *, sysid: int = 245, compid: int = 190,
              seq: int = 0, incompat: int = 0) -> bytes:
    """A MAVLink 2 frame of ``msgid`` around any ``payload``, with a good checksum."""
    cls = mavlink.mavlink_map.get(msgid)
    header = bytes((0xFD, len(payload), incompat, 0, seq & 0xFF, sysid, compid,
                    msgid & 0xFF, (msgid >> 8) & 0xFF, msgid >> 16))
    crc = frame_crc(header[1:] + payload, cls.crc_extra if cls is not None else 0)
    return header + payload + struct.pack("<H", crc)


def field_layout(msgid: int) -> list[tuple[str, int, str, int]]:
    """(field, offset, struct code, count) of each field of a message type, in wire order."""
    cls = mavlink.mavlink_map[msgid]
    out: list[tuple[str, int, str, int]] = []
    offset, count = 0, ""
    names = iter(cls.ordered_fieldnames)
    for code in cls.unpacker.format.lstrip("<"):
        if code.isdigit():
            count += code
            continue
        n = int(count or "1")
        count = ""
        out.append((next(names), offset, code, n))
        offset += struct.calcsize("<" + code) * n
    return out
