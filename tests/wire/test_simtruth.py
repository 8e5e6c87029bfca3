"""The sim's truth samples on the wire: a round trip, and malformed samples named."""

from __future__ import annotations

import json

import pytest

from gcs.wire import SimTruth

SAMPLE = SimTruth(t=1.5, ids=(1, 2), vehicle_p_ned=((0.0, 1.0, -2.0), (1.0, 0.0, -2.0)),
                  payload_p_ned=(0.5, 0.5, -1.0), payload_v_ned=(0.1, 0.0, 0.0),
                  rope_tension=(1.2, 1.3))


def test_round_trip() -> None:
    assert SimTruth.from_bytes(SAMPLE.to_bytes()) == SAMPLE


@pytest.mark.parametrize(("field", "value", "named"), [
    ("payload_p_ned", [0.5, 0.5], "payload_p_ned: 2 values, not 3"),
    ("payload_v_ned", [0.1, 0.0, 0.0, 9.0], "payload_v_ned: 4 values, not 3"),
    ("vehicle_p_ned", [[0.0, 1.0, -2.0], [1.0, 0.0]], "vehicle_p_ned: 2 values, not 3"),
    ("vehicle_p_ned", [[0.0, 1.0, -2.0]], "vehicle_p_ned: 1 entries for 2 vehicles"),
    ("rope_tension", [1.2, 1.3, 1.4], "rope_tension: 3 entries for 2 vehicles"),
    ("t", "soon", "could not convert"),
    ("ids", None, "not iterable"),
])
def test_malformed_samples_are_refused_naming_the_fault(field: str, value: object,
                                                         named: str) -> None:
    d = json.loads(SAMPLE.to_bytes())
    d[field] = value
    with pytest.raises(ValueError, match="malformed sim truth sample") as info:
        SimTruth.from_bytes(json.dumps(d).encode())
    assert named in str(info.value)


def test_a_missing_field_is_named() -> None:
    d = json.loads(SAMPLE.to_bytes())
    del d["rope_tension"]
    with pytest.raises(ValueError, match="rope_tension"):
        SimTruth.from_bytes(json.dumps(d).encode())
