"""Wire format of the sim clock and of lockstep acknowledgements on zenoh.

Why: the GCS follows the simulator's time in headless runs, and a lockstep
GCS tells the simulator how far it has got; both sides must read the same
bytes. One sample is 8 bytes: the sim time in seconds as a little-endian
IEEE-754 float64 (``struct.pack("<d", t)``), published on
``fleet/<fleet>/clock`` by the sim and on ``fleet/<fleet>/clock/ack`` by the
GCS (:func:`gcs.wire.keys.clock`, :func:`gcs.wire.keys.clock_ack`).

A lockstep sim appends to its clock samples how many ground-truth samples it
has published so far (uint32), then per vehicle 5 bytes: the system id
(uint8) and how many MAVLink payloads that vehicle has published so far
(uint32); all little-endian, counts modulo 2^32. Why: the clock travels at
real-time priority and on its own callback thread, so it can overtake the
telemetry and truth sent before it; with the counts, a GCS can wait until it
holds everything sent up to that time, and a headless flight sees the same
data at each tick on every run.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Mapping
from dataclasses import dataclass, field

__all__ = ["CLOCK_FORMAT", "ClockSample", "decode_clock", "decode_time", "encode_clock",
           "encode_time"]

CLOCK_FORMAT = struct.Struct("<d")
"""8-byte little-endian float64 seconds."""

_TRUTH = struct.Struct("<I")
"""After the time, in a lockstep clock sample: ground-truth samples published."""
_SENT = struct.Struct("<BI")
"""Then per vehicle: system id, MAVLink payloads published."""


@dataclass(frozen=True)
class ClockSample:
    """A clock sample: sim time (s) and, from a lockstep sim, what was published so far."""

    t: float
    truth: int | None = None
    """Ground-truth samples published (None: a plain sample)."""
    sent: Mapping[int, int] = field(default_factory=dict)
    """MAVLink payloads published per vehicle system id."""


def encode_clock(t: float, truth: int | None = None,
                 sent: Mapping[int, int] | None = None) -> bytes:
    """Clock payload for sim time ``t`` (s); with the counts (lockstep) if ``truth`` is given."""
    if truth is None:
        return encode_time(t)
    return (encode_time(t) + _TRUTH.pack(truth % 2**32)
            + b"".join(_SENT.pack(sysid, count % 2**32) for sysid, count in (sent or {}).items()))


def decode_clock(data: bytes) -> ClockSample:
    """:class:`ClockSample` from a clock payload; ValueError naming what is wrong."""
    if len(data) == CLOCK_FORMAT.size:
        return ClockSample(decode_time(data))
    head = CLOCK_FORMAT.size + _TRUTH.size
    if len(data) < head or (len(data) - head) % _SENT.size:
        raise ValueError(f"clock sample must be {CLOCK_FORMAT.size} bytes, or {head} plus "
                         f"{_SENT.size} per vehicle, got {len(data)}")
    t = decode_time(data[:CLOCK_FORMAT.size])
    (truth,) = _TRUTH.unpack_from(data, CLOCK_FORMAT.size)
    return ClockSample(t, truth, dict(_SENT.iter_unpack(data[head:])))


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
