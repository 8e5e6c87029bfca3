"""Wire format of the sim clock and of lockstep acknowledgements on zenoh.

Why: the GCS follows the simulator's time in headless runs, and a lockstep
GCS tells the simulator how far it has got; both sides must read the same
bytes. One sample is 8 bytes: the sim time in seconds as a little-endian
IEEE-754 float64 (``struct.pack("<d", t)``), published on
``fleet/<fleet>/clock`` by the sim and on ``fleet/<fleet>/clock/ack`` by the
GCS (:func:`gcs.link.keys.clock`, :func:`gcs.link.keys.clock_ack`).
"""

from __future__ import annotations

import math
import struct

__all__ = ["CLOCK_FORMAT", "decode_time", "encode_time"]

CLOCK_FORMAT = struct.Struct("<d")
"""8-byte little-endian float64 seconds."""


def encode_time(t: float) -> bytes:
    """Payload for sim time ``t`` (s)."""
    return CLOCK_FORMAT.pack(float(t))


def decode_time(data: bytes) -> float:
    """Sim time (s) from a payload; ValueError if it is not 8 bytes holding a finite time >= 0."""
    if len(data) != CLOCK_FORMAT.size:
        raise ValueError(f"clock sample must be {CLOCK_FORMAT.size} bytes, got {len(data)}")
    (t,) = CLOCK_FORMAT.unpack(data)
    if not math.isfinite(t) or t < 0.0:
        raise ValueError(f"clock sample must be a finite time >= 0 s, got {t}")
    return t
