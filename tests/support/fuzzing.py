"""What the fuzz tests (``tests/fuzz/``) share: settings, strategies, checks.

Each fuzz test feeds one entry point that takes bytes from the network with
generated inputs and checks, for every input: no exception escapes except the
documented ``ValueError`` refusals, no input takes long (no hang), nothing is
written to stderr, every refusal is counted. ``bench/fuzz.py`` runs the same
entry points with 10^6 inputs each.
"""

from __future__ import annotations

import json
import logging
import math
import struct
import time
from collections.abc import Iterator
from contextlib import contextmanager

import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

from gcs.testing import field_layout, raw_frame
from gcs.wire import mavlink

MAX_INPUT_S = 1.0
"""An input that takes longer than this is a hang."""


def fuzz_settings(max_examples: int) -> settings:
    """Hypothesis settings of a fuzz test: the same inputs on every run (no flaky suite;
    ``bench/fuzz.py --seed`` explores), no example database written into the checkout."""
    return settings(max_examples=max_examples, deadline=None, database=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.function_scoped_fixture,
                                           HealthCheck.filter_too_much])


@contextmanager
def timed() -> Iterator[None]:
    """Fails if the block takes longer than :data:`MAX_INPUT_S` of this thread's CPU time
    (a busy machine that deschedules the test is no hang)."""
    start = time.thread_time()
    yield
    elapsed = time.thread_time() - start
    assert elapsed < MAX_INPUT_S, f"one input took {elapsed:.3f} s"


def assert_quiet(capfd: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture) -> None:
    """Nothing on stderr, and no traceback logged."""
    err = capfd.readouterr().err
    assert err == "", err[:2000]
    tracebacks = [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]
    assert not tracebacks, [r.getMessage() for r in tracebacks[:5]]


# -- strategies ---------------------------------------------------------------------------------

special_floats = st.sampled_from([math.nan, math.inf, -math.inf, 3.4e38, -3.4e38, 1e-45, 0.0,
                                  -0.0, 1.0, -1.0, 1e7, 1.7976931348623157e308])
"""Floats random bytes rarely make."""


BATCH = 10
"""Inputs per hypothesis example: a fuzz test of 1000 examples feeds 10^4 inputs (drawing
an example costs more than most inputs take)."""


def batches(inputs: st.SearchStrategy[bytes]) -> st.SearchStrategy[list[bytes]]:
    """:data:`BATCH` inputs at a time."""
    return st.lists(inputs, min_size=BATCH, max_size=BATCH)


_INTS = (0, 1, -1, 2, 3, 4, 255, 256, 2**31, -(2**63), 2**64, 10**30, 10**400)
_FLOATS = (0.5, -0.0, 1e-300, -1e300, 1e308, math.inf, -math.inf, math.nan, 2.5, -7.25)
_STRINGS = ("", "kill", "cut", "restore", "KILL", "\x00", "\u00e9", "a" * 60)
_KEYS = ("action", "sysid", "t", "ids", "vehicle_p_ned", "payload_p_ned", "payload_v_ned",
         "rope_tension", "x")


def json_from_bytes(data: bytes) -> object:
    """A JSON value grown from ``data``, each byte choosing the next production: cheap to
    draw (a recursive hypothesis strategy costs milliseconds per value) and it still
    shrinks with the bytes."""
    it = iter(data)

    def byte() -> int:
        return next(it, 0)

    def value(depth: int) -> object:
        kind = byte() % (10 if depth < 6 else 7)
        if kind == 0:
            return None
        if kind == 1:
            return bool(byte() & 1)
        if kind == 2:
            return _INTS[byte() % len(_INTS)]
        if kind == 3:
            return _FLOATS[byte() % len(_FLOATS)]
        if kind == 4:
            return _STRINGS[byte() % len(_STRINGS)]
        if kind in (5, 6):
            return byte() - 20
        if kind in (7, 8):
            return [value(depth + 1) for _ in range(byte() % 5)]
        return {_KEYS[byte() % len(_KEYS)]: value(depth + 1) for _ in range(byte() % 5)}

    return value(0)


json_values = st.binary(max_size=48).map(json_from_bytes)
"""Any JSON value: nesting, huge integers, NaN, infinities, odd strings."""


def to_json(value: object) -> bytes:
    return json.dumps(value).encode("utf-8", "surrogatepass")


hostile_json = st.builds(
    lambda piece, k: piece * k,
    st.sampled_from([b'{"a":', b"[", b"[]", b"1", b"9", b"-", b'"\\u', b"\xff", b"{"]),
    st.integers(min_value=1, max_value=20_000)) | st.sampled_from(
    [b"NaN", b"Infinity", b"-Infinity", b"1e999", b"[" * 1000 + b"]" * 1000])
"""Deep nesting, long numbers, broken escapes, bytes that are not UTF-8."""


def mutate(data: bytes, ops: bytes) -> bytes:
    """``data`` with a few bytes flipped, inserted, deleted or cut off, as ``ops`` says
    (three bytes an operation: which, where, what)."""
    out = bytearray(data)
    for k in range(0, len(ops) - 2, 3):
        op, at, value = ops[k] % 4, ops[k + 1] * 257 % max(1, len(out)), ops[k + 2]
        if op == 0 and out:
            out[at] = value
        elif op == 1:
            out.insert(at, value)
        elif op == 2 and out:
            del out[at]
        elif out:
            del out[at:]
    return bytes(out)


mutations = st.binary(min_size=3, max_size=12)
"""Operations for :func:`mutate`: ``st.builds(mutate, real_inputs, mutations)``."""


_F64 = (math.nan, math.inf, -math.inf, 1.7976931348623157e308, -1e300, 5e-324, 0.0, -0.0, 1.0,
        -1.0, 1e7, 0.25)
_F32 = (math.nan, math.inf, -math.inf, 3.4e38, -3.4e38, 1e-45, 0.0, -0.0, 1.0, -1.0, 1e7, 0.25)


def payload_from_bytes(msgid: int, raw: bytes, choices: bytes,
                       target: int | None = None) -> bytes:
    """A payload of message type ``msgid``: the field values from ``raw`` (padded or cut to
    the type's length), and ``choices`` (a byte per field, one more) makes floats often
    special (NaN, infinities, the largest, the smallest), addresses it to ``target`` (its
    component 1, or broadcast) and trims trailing zeros as MAVLink 2 does."""
    size = mavlink.mavlink_map[msgid].unpacker.size
    out = bytearray(raw[:size].ljust(size, b"\x00"))
    fields = field_layout(msgid)
    choices = choices.ljust(len(fields) + 1, b"\xff")
    for (name, offset, code, n), c in zip(fields, choices, strict=False):
        if code in "fd" and c < 96:
            table = _F64 if code == "d" else _F32
            for k in range(n):
                struct.pack_into("<" + code, out, offset + k * struct.calcsize(code),
                                 table[(c + k) % len(table)])
        elif target is not None and name == "target_system" and c < 192:
            out[offset] = (target, 0)[c & 1]
        elif target is not None and name == "target_component" and c < 192:
            out[offset] = (1, 0)[c & 1]
    if choices[len(fields)] & 1:
        out = bytearray(out.rstrip(b"\x00"))
    return bytes(out)


def payloads(msgid: int, target: int | None = None) -> st.SearchStrategy[bytes]:
    """Payloads of message type ``msgid`` with arbitrary field values
    (:func:`payload_from_bytes`)."""
    size = mavlink.mavlink_map[msgid].unpacker.size
    return st.builds(lambda raw, choices: payload_from_bytes(msgid, raw, choices, target),
                     st.binary(min_size=size, max_size=size),
                     st.binary(min_size=len(field_layout(msgid)) + 1,
                               max_size=len(field_layout(msgid)) + 1))


def datagram_from_bytes(msgids: list[int], target: int | None, data: bytes) -> bytes:
    """What a datagram could carry, grown from ``data`` (its first byte chooses): noise,
    whole frames of ``msgids`` with arbitrary field values and good checksums, or such
    frames mutated, in noise or cut short. One hypothesis draw per datagram: drawing each
    part would cost more than the decoding fuzzed."""
    if len(data) < 4:
        return data
    kind, count, rest = data[0] % 5, 1 + data[1] % 3, data[2:]
    if kind == 0:
        return rest
    parts = []
    for _ in range(count):
        msgid = msgids[int.from_bytes(rest[:2].ljust(2, b"\x00"), "little") % len(msgids)]
        size = mavlink.mavlink_map[msgid].unpacker.size
        n_choices = len(field_layout(msgid)) + 1
        payload = payload_from_bytes(msgid, rest[3:3 + size], rest[3 + size:3 + size + n_choices],
                                     target)
        parts.append(raw_frame(msgid, payload, seq=rest[2] if len(rest) > 2 else 0))
        rest = rest[3 + size + n_choices:]
    out = b"".join(parts)
    if kind == 2:
        return mutate(out, rest[:12] or b"\x00\x00\x00")
    if kind == 3:
        cut = len(rest) // 2
        return rest[:cut][:20] + out + rest[cut:][:20]
    if kind == 4:
        return out[:(rest[0] if rest else 0) * len(out) // 256]
    return out


def datagrams(msgids: list[int], target: int | None = None) -> st.SearchStrategy[bytes]:
    """Datagrams of :func:`datagram_from_bytes`."""
    return st.binary(min_size=4, max_size=700).map(
        lambda data: datagram_from_bytes(msgids, target, data))
