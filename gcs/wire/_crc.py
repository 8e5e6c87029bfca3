"""MAVLink's frame checksum (CRC-16/MCRF4XX with the message type's CRC_EXTRA byte).

Why one module: the encoder, the decoder and the log reader all check or
write it per frame, and fastcrc (which pymavlink also uses when installed)
computes it in a fraction of the time of the pure Python fallback.
"""

from __future__ import annotations

from gcs.wire._dialect import mavlink

__all__ = ["frame_crc"]

_FAST = getattr(mavlink, "mcrf4xx", None)
_BYTE = tuple(bytes((b,)) for b in range(256))


def frame_crc(body: bytes | bytearray | memoryview, crc_extra: int) -> int:
    """Checksum of a frame's ``body`` (bytes after the start marker, before the checksum)."""
    if _FAST is not None:  # chained: the body is not copied to append one byte
        return int(_FAST(_BYTE[crc_extra], _FAST(body, 0xFFFF)))
    return int(mavlink.x25crc(bytes(body) + _BYTE[crc_extra]).crc)
