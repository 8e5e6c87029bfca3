"""Fuzzing telemetry decoding at the GCS (``gcs.wire.TelemetryStore.update``): every message
type, arbitrary field values.

An ATTITUDE with infinite angles raised "math domain error" on the receive
thread, a traceback per message. Whatever a vehicle sends, decoded by the
GCS's own decoder, the store gives a record of finite values within
``TELEMETRY_MAX_ABS``, or refuses and counts the message, or (not telemetry)
ignores it. ``bench/fuzz.py --only telemetry`` runs 10^6 inputs.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterator

import pytest
from hypothesis import given

from gcs.wire import (
    TELEMETRY_MAX_ABS,
    Attitude,
    FrameDecoder,
    LocalPosition,
    TelemetryStore,
    ThrustTarget,
    mavlink,
)
from gcs.wire._telemetry import Imu
from tests.support.fuzzing import assert_quiet, batches, datagrams, fuzz_settings, timed

TELEMETRY = [mavlink.MAVLINK_MSG_ID_HEARTBEAT, mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED,
             mavlink.MAVLINK_MSG_ID_ATTITUDE, mavlink.MAVLINK_MSG_ID_ATTITUDE_QUATERNION,
             mavlink.MAVLINK_MSG_ID_HIGHRES_IMU, mavlink.MAVLINK_MSG_ID_SYS_STATUS,
             mavlink.MAVLINK_MSG_ID_STATUSTEXT, mavlink.MAVLINK_MSG_ID_ATTITUDE_TARGET]
"""The types the store keeps."""
MEASURED = (LocalPosition, Attitude, Imu)
"""Records of measured values, each bounded by TELEMETRY_MAX_ABS."""


def floats(value: object) -> Iterator[float]:
    if isinstance(value, float):
        yield value
    elif isinstance(value, tuple):
        for v in value:
            yield from floats(v)


def test_telemetry_of_any_value_is_stored_finite_or_refused_and_counted(
        capfd: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture) -> None:
    decoder = FrameDecoder(datagram=True)
    store = TelemetryStore(1)
    outcomes: Counter[str] = Counter()

    @fuzz_settings(1300)  # each outcome over 100 times with ATTITUDE_TARGET among the types
    @given(batches(datagrams(TELEMETRY) | datagrams(TELEMETRY)
                   | datagrams(sorted(mavlink.mavlink_map))))
    def fuzz(inputs: list[bytes]) -> None:
        for data in inputs:
            for msg in decoder.feed(data):
                refused = store.refused
                with timed():
                    record = store.update(msg, 1.0)
                kept = msg.get_msgId() in TELEMETRY
                if record is None:
                    outcomes["refused" if kept else "ignored"] += 1
                    assert store.refused == refused + kept
                    continue
                outcomes["stored"] += 1
                assert kept and store.refused == refused
                if isinstance(record, MEASURED):
                    values = [v for name in ("p_ned", "v_ned", "q_wxyz", "rpy", "rates_body",
                                             "accel_body", "gyro_body")
                              for v in floats(getattr(record, name, ()))]
                    assert all(math.isfinite(v) for v in values), record
                    assert all(abs(v) <= TELEMETRY_MAX_ABS for v in values), record
                if isinstance(record, ThrustTarget):  # a fraction of the autopilot's thrust
                    assert -1.0 <= record.thrust <= 1.0, record
                assert store.snapshot() is not None

    fuzz()
    assert_quiet(capfd, caplog)
    assert min(outcomes["stored"], outcomes["refused"], outcomes["ignored"]) > 100, outcomes
