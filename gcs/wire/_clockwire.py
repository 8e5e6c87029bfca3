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

A lockstep sim follows one GCS, its partner: the first whose ack it took. A
GCS's ack is 12 bytes: the time (float64) and the GCS's partner id (uint32,
drawn at random by each GCS, never 0); an ack of the time alone (8 bytes) is
partner 0's. Once bound, the sim's clock samples name the partner as an entry
of system id 0 (no vehicle has it) holding the partner id. Why: a second GCS
joining the same simulator reads that it is not the partner and stops instead
of flying the vehicles beside the first.

Anyone on the zenoh fabric can publish a clock sample, so a follower checks
each one against the time it follows (:class:`ClockGuard`): a sample that runs
backwards or jumps far ahead is refused and counted, never adopted.
"""

from __future__ import annotations

import math
import statistics
import struct
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from enum import Enum

__all__ = ["ACK_FORMAT", "CLOCK_FORMAT", "CLOCK_MAX_BYTES", "ClockGuard", "ClockSample",
           "ClockVerdict", "decode_ack", "decode_clock", "decode_time", "encode_ack",
           "encode_clock", "encode_time"]

CLOCK_FORMAT = struct.Struct("<d")
"""8-byte little-endian float64 seconds."""

_TRUTH = struct.Struct("<I")
"""After the time, in a lockstep clock sample: ground-truth samples published."""
_SENT = struct.Struct("<BI")
"""Then per vehicle: system id, MAVLink payloads published (system id 0: the partner id)."""

_PARTNER_SYSID = 0

ACK_FORMAT = struct.Struct("<dI")
"""A lockstep ack: the tick's time (float64 s) and the acking GCS's partner id (uint32)."""

CLOCK_MAX_BYTES = CLOCK_FORMAT.size + _TRUTH.size + 256 * _SENT.size
"""Longest clock sample, bytes: a lockstep sample of 255 vehicles (system ids 1..255) and
its partner."""


@dataclass(frozen=True)
class ClockSample:
    """A clock sample: sim time (s) and, from a lockstep sim, what was published so far."""

    t: float
    truth: int | None = None
    """Ground-truth samples published (None: a plain sample)."""
    sent: Mapping[int, int] = field(default_factory=dict)
    """MAVLink payloads published per vehicle system id."""
    partner: int | None = None
    """Partner id of the GCS whose acks the lockstep sim follows (None: none yet)."""


def encode_clock(t: float, truth: int | None = None,
                 sent: Mapping[int, int] | None = None, partner: int | None = None) -> bytes:
    """Clock payload for sim time ``t`` (s); with the counts (lockstep) if ``truth`` is given,
    and its ``partner`` once it has one."""
    if truth is None:
        return encode_time(t)
    entries = dict(sent or {})
    if partner is not None:
        entries[_PARTNER_SYSID] = partner
    return (encode_time(t) + _TRUTH.pack(truth % 2**32)
            + b"".join(_SENT.pack(sysid, count % 2**32) for sysid, count in entries.items()))


def decode_clock(data: bytes) -> ClockSample:
    """:class:`ClockSample` from a clock payload; ValueError naming what is wrong (at most
    :data:`CLOCK_MAX_BYTES`, each vehicle once)."""
    if len(data) == CLOCK_FORMAT.size:
        return ClockSample(decode_time(data))
    head = CLOCK_FORMAT.size + _TRUTH.size
    if len(data) > CLOCK_MAX_BYTES:
        raise ValueError(f"clock sample of {len(data)} bytes, more than {CLOCK_MAX_BYTES} "
                         "(255 vehicles)")
    if len(data) < head or (len(data) - head) % _SENT.size:
        raise ValueError(f"clock sample must be {CLOCK_FORMAT.size} bytes, or {head} plus "
                         f"{_SENT.size} per vehicle, got {len(data)}")
    t = decode_time(data[:CLOCK_FORMAT.size])
    (truth,) = _TRUTH.unpack_from(data, CLOCK_FORMAT.size)
    sent = dict(_SENT.iter_unpack(data[head:]))
    if len(sent) * _SENT.size != len(data) - head:
        raise ValueError("clock sample names a vehicle twice")
    partner = sent.pop(_PARTNER_SYSID, None)
    return ClockSample(t, truth, sent, partner)


def encode_ack(t: float, partner: int) -> bytes:
    """Lockstep ack of the tick at ``t`` (s) by the GCS whose partner id is ``partner``."""
    return ACK_FORMAT.pack(float(t), partner)


def decode_ack(data: bytes) -> tuple[float, int]:
    """Time (s) and partner id of a lockstep ack (0: the time alone); ValueError naming
    what is wrong."""
    if len(data) == CLOCK_FORMAT.size:
        return decode_time(data), 0
    if len(data) != ACK_FORMAT.size:
        raise ValueError(f"clock ack must be {CLOCK_FORMAT.size} or {ACK_FORMAT.size} bytes, "
                         f"got {len(data)}")
    (partner,) = struct.unpack_from("<I", data, CLOCK_FORMAT.size)
    return decode_time(data[:CLOCK_FORMAT.size]), partner


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


class ClockVerdict(Enum):
    """What a :class:`ClockGuard` made of one sample."""

    FIRST = "the first sample"
    FORWARD = "forward"
    REPEATED = "the same time again"
    REANCHORED = "a new time line, followed"
    BACKWARDS = "runs backwards"
    JUMP = "jumps too far ahead"
    NOT_FINITE = "not a finite time >= 0"

    @property
    def accepted(self) -> bool:
        """Whether the follower adopts the sample."""
        return self in _ADOPTED


_ADOPTED = frozenset({ClockVerdict.FIRST, ClockVerdict.FORWARD, ClockVerdict.REPEATED,
                      ClockVerdict.REANCHORED})


class ClockGuard:
    """Which sim clock samples a follower adopts: forwards, and in bounded steps.

    Why: the clock key is open to anyone on the fabric, and a follower's clock
    never runs backwards, so one forged sample far ahead would be for good: a
    GCS's clock thrown years ahead reads every vehicle as "no fresh telemetry
    for 999999970 s", aborts the flight and stamps the log decades on.

    Rules: the first sample is adopted whatever its time (a GCS joins a running
    sim late). Later samples are adopted if they repeat the last time (a
    lockstep sim repeats its clock while it waits) or run ahead of it by at
    most :attr:`bound`: ``max(min_jump_s, step_factor x`` the median of the
    last steps``)``, 5 s or 50 typical steps (the sim's step is 1/128 s, so 5 s),
    and never more than ``max_bound_s`` (60 s), so that big steps cannot widen
    the bound without end. Samples that run backwards, jump further or are not
    finite are refused and counted (:attr:`refused`).

    The sim's own clock can still leap once (a follower that stalled while a
    fast sim ran on and its samples were dropped): a refused jump is followed
    when its time line has gone on consistently (each sample within the bound
    of the one before) for ``confirm_s`` of wall time while nothing of the
    time line being followed was heard (:attr:`reanchored` counts these). A
    forger who publishes beside a live sim never gets there: every sample of
    the real clock (at, behind or not far ahead of the time followed) resets
    the candidate.

    Not thread-safe: one per subscriber (zenoh delivers one key's samples in order).
    """

    def __init__(self, *, min_jump_s: float = 5.0, step_factor: float = 50.0,
                 max_bound_s: float = 60.0, confirm_s: float = 1.0, history: int = 32,
                 wall_clock: Callable[[], float] = time.monotonic) -> None:
        self._min_jump = min_jump_s
        self._max_bound = max(max_bound_s, min_jump_s)
        self._factor = step_factor
        self._confirm = confirm_s
        self._wall = wall_clock
        self._steps: deque[float] = deque(maxlen=history)
        self._bound = min_jump_s
        self._last: float | None = None
        self._candidate: tuple[float, float] | None = None  # (its latest time, wall at start)
        self.refused = 0
        """Samples refused so far."""
        self.reanchored = 0
        """Times a new time line was followed after a refused jump."""

    @property
    def last(self) -> float | None:
        """The last adopted time, s (None before the first sample)."""
        return self._last

    @property
    def bound(self) -> float:
        """How far ahead of the last adopted time a sample may be, s."""
        return self._bound

    def check(self, t: float) -> ClockVerdict:
        """Judge sample time ``t`` (s); adopts it if the verdict is ``accepted``."""
        verdict = self._judge(t)
        if not verdict.accepted:
            self.refused += 1
        return verdict

    def _judge(self, t: float) -> ClockVerdict:
        if not (math.isfinite(t) and t >= 0.0):
            return ClockVerdict.NOT_FINITE
        last = self._last
        if last is None:
            self._last = t
            return ClockVerdict.FIRST
        if t == last:
            self._candidate = None
            return ClockVerdict.REPEATED
        if t < last:
            self._candidate = None  # the time line followed is not silent
            return ClockVerdict.BACKWARDS
        if t - last <= self._bound:
            self._steps.append(t - last)
            self._bound = min(self._max_bound, max(
                self._min_jump, self._factor * statistics.median(self._steps)))
            self._last = t
            self._candidate = None
            return ClockVerdict.FORWARD
        return self._jump(t)

    def _jump(self, t: float) -> ClockVerdict:
        """A sample too far ahead: refused, unless it confirms a new time line."""
        now = self._wall()
        candidate = self._candidate
        if candidate is None or not 0.0 <= t - candidate[0] <= self._bound:
            self._candidate = (t, now)  # a new candidate time line starts here
            return ClockVerdict.JUMP
        self._candidate = (t, candidate[1])
        if now - candidate[1] < self._confirm:
            return ClockVerdict.JUMP
        self._last = t
        self._candidate = None
        self.reanchored += 1
        return ClockVerdict.REANCHORED
