"""Fuzzing the sim clock at a follower: decoding (``gcs.wire.decode_clock``) and the guard
(``gcs.wire.ClockGuard``) that decides which samples a GCS adopts.

Anyone on the fabric can publish on ``fleet/<fleet>/clock``; forged samples
threw a GCS's clock to t = 1e9 s. Whatever the bytes, decoding gives a sample
or a ValueError; whatever the samples, beside a real clock that goes on, the
guard never adopts a time that is not finite, never goes back, never jumps
further than its bound, and counts every sample it refuses.
``bench/fuzz.py --only clock`` runs 10^6 inputs.
"""

from __future__ import annotations

import math
import struct
from collections import Counter

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcs.wire import CLOCK_MAX_BYTES, ClockGuard, ClockVerdict, decode_clock, encode_clock
from tests.support.fuzzing import (
    assert_quiet,
    fuzz_settings,
    mutate,
    mutations,
    special_floats,
    timed,
)

REAL_STEPS = (1 / 128, 1 / 128, 0.25, 0.0, 3 / 128)
"""How the sim's own clock moves between two samples a follower hears."""

counts = st.dictionaries(st.integers(0, 255), st.integers(0, 2**32 - 1), max_size=6)
forged = (
    st.builds(lambda t: struct.pack("<d", t), special_floats | st.floats())
    | st.builds(lambda t, truth, sent: encode_clock(t, truth, sent),
                st.floats(0, 1e12), st.integers(0, 2**32 - 1), counts)
    | st.builds(mutate, st.builds(encode_clock, st.floats(0, 100), st.integers(0, 9), counts),
                mutations)
    | st.binary(max_size=40)
    | st.sampled_from([7, 9, 13, 17, CLOCK_MAX_BYTES, CLOCK_MAX_BYTES + 5]).map(bytes))
"""Samples a forger could send."""

# each step: None (the real clock goes on), or forged bytes
steps = st.lists(st.none() | st.none() | forged, min_size=15, max_size=15)


def test_a_follower_adopts_only_the_real_clock_and_counts_the_rest(
        capfd: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture) -> None:
    outcomes: Counter[str] = Counter()

    @fuzz_settings(700)
    @given(steps, st.sampled_from(REAL_STEPS), st.floats(0, 1e6))
    def fuzz(sequence: list[bytes | None], step: float, start: float) -> None:
        guard = ClockGuard()
        real = start
        assert guard.check(real) is ClockVerdict.FIRST  # a follower trusts its first sample
        for item in sequence:
            if item is None:
                real += step
                data = encode_clock(real)
            else:
                data = item
            outcomes["inputs"] += 1
            with timed():
                try:
                    sample = decode_clock(data)
                except ValueError as exc:
                    assert str(exc)
                    outcomes["malformed"] += 1
                    continue
            assert len(data) <= CLOCK_MAX_BYTES
            assert math.isfinite(sample.t) and sample.t >= 0.0
            entries = len(sample.sent) + (sample.partner is not None)  # partner: system id 0
            assert len(data) in (8, 12 + 5 * entries)
            last, bound, refused = guard.last, guard.bound, guard.refused
            assert last is not None
            verdict = guard.check(sample.t)
            if verdict.accepted:
                outcomes["adopted"] += 1
                assert guard.last == sample.t >= last, (last, sample.t)
                assert verdict is ClockVerdict.REANCHORED or sample.t - last <= bound
                assert guard.refused == refused
            else:
                outcomes["refused"] += 1
                assert guard.last == last and guard.refused == refused + 1
                assert sample.t < last or sample.t - last > bound, (last, sample.t, bound)
        # the real clock is never refused (a forger can only run it ahead within the bound)
        assert guard.last is not None and guard.last >= real

    fuzz()
    assert_quiet(capfd, caplog)
    assert outcomes["inputs"] >= 10_000, outcomes
    assert min(outcomes["adopted"], outcomes["refused"], outcomes["malformed"]) > 500, outcomes
