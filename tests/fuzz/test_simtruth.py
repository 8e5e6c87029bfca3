"""Fuzzing the sim's truth samples at a viewer (``gcs.wire.SimTruth.from_bytes``).

Anyone on the fabric can publish on ``fleet/<fleet>/sim/truth``; nested JSON
raised RecursionError and a number too large for a float OverflowError out of
the decoder, onto zenoh's callback thread. Whatever the bytes, it gives a
sample of finite values or a ValueError. ``bench/fuzz.py --only sim_truth``
runs 10^6 inputs.
"""

from __future__ import annotations

import json
import math
from collections import Counter

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcs.wire import TRUTH_MAX_BYTES, SimTruth
from tests.support.fuzzing import (
    assert_quiet,
    batches,
    fuzz_settings,
    hostile_json,
    json_values,
    mutate,
    mutations,
    timed,
    to_json,
)


def truth_from_bytes(data: bytes) -> bytes:
    """A real sample (1 to 6 vehicles, values in +-327 m) grown from ``data``: cheap to
    draw, where a hypothesis float costs a tenth of a millisecond."""
    data = data.ljust(64, b"\x00")
    n = 1 + data[0] % 6
    values = [(int.from_bytes(data[k:k + 2], "little") - 32768) / 100.0
              for k in range(1, 63, 2)]

    def v(k: int) -> float:
        return values[k % len(values)]

    return SimTruth(t=abs(v(0)) * 100.0, ids=tuple(range(1, n + 1)),
                    vehicle_p_ned=tuple((v(3 * k + 1), v(3 * k + 2), v(3 * k + 3))
                                        for k in range(n)),
                    payload_p_ned=(v(20), v(21), v(22)), payload_v_ned=(v(23), v(24), v(25)),
                    rope_tension=tuple(abs(v(26 + k)) for k in range(n))).to_bytes()


truths = st.binary(min_size=1, max_size=64).map(truth_from_bytes)
"""Real samples, as the sim writes them."""


def _replace(sample: bytes, key_choice: int, value: object, inner: bool) -> bytes:
    doc = json.loads(sample)
    key = sorted(doc)[key_choice % len(doc)]
    if inner and isinstance(doc[key], list) and doc[key]:
        doc[key][key_choice % len(doc[key])] = value
    else:
        doc[key] = value
    return to_json(doc)


truth_inputs = (truths | st.builds(mutate, truths, mutations)
                | st.builds(_replace, truths, st.integers(0, 99), json_values, st.booleans())
                | json_values.map(to_json) | hostile_json | st.binary(max_size=400))


def test_the_truth_decoder_returns_a_finite_sample_or_refuses_with_a_value_error(
        capfd: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture) -> None:
    outcomes: Counter[str] = Counter()

    @fuzz_settings(1000)
    @given(batches(truth_inputs))
    def fuzz(inputs: list[bytes]) -> None:
        for data in inputs:
            with timed():
                try:
                    truth = SimTruth.from_bytes(data)
                except ValueError as exc:
                    outcomes["refused"] += 1
                    assert str(exc).startswith("malformed sim truth sample")
                    continue
            outcomes["accepted"] += 1
            assert len(data) <= TRUTH_MAX_BYTES
            n = len(truth.ids)
            assert len(set(truth.ids)) == n and all(1 <= i <= 255 for i in truth.ids)
            assert len(truth.vehicle_p_ned) == len(truth.rope_tension) == n
            values = (truth.t, *truth.payload_p_ned, *truth.payload_v_ned, *truth.rope_tension,
                      *(x for p in truth.vehicle_p_ned for x in p))
            assert all(isinstance(x, float) and math.isfinite(x) for x in values)
            assert SimTruth.from_bytes(truth.to_bytes()) == truth

    fuzz()
    assert_quiet(capfd, caplog)
    assert sum(outcomes.values()) == 10_000
    assert outcomes["accepted"] > 1000 and outcomes["refused"] > 3000, outcomes
