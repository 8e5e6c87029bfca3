"""Column decoding of logged frames agrees with pymavlink's decode, field by field."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from gcs.flightlog import TlogIndex
from gcs.flightlog._columns import CHUNK, decode_columns, wire_dtype
from gcs.wire import mavlink

_NAMES = ("LOCAL_POSITION_NED", "SYS_STATUS", "DEBUG_FLOAT_ARRAY", "HEARTBEAT", "STATUSTEXT")


def _message(kind: int, k: int, rng: np.random.Generator) -> object:
    if kind == 0:
        return mavlink.MAVLink_local_position_ned_message(k, *rng.normal(size=6).tolist())
    if kind == 1:  # the extension fields are zero in some (trimmed) and absent in MAVLink 1
        return mavlink.MAVLink_sys_status_message(
            1, 2, 3, 4, 12000, -1, int(rng.integers(-1, 100)), 0, 0, 0, 0, 0, 0, 0, 0,
            0 if k % 5 else 7)
    if kind == 2:  # all-zero data: the payload is trimmed down to its header fields
        data = rng.normal(size=58).tolist() if k % 3 else [0.0] * 58
        return mavlink.MAVLink_debug_float_array_message(k, b"abc", k % 300, data)
    if kind == 3:
        return mavlink.MAVLink_heartbeat_message(2, 12, 0x80 if k % 2 else 0, k, 3, 3)
    return mavlink.MAVLink_statustext_message(k % 8, f"text {k}".encode(), 0, 0)


def _write_log(path: Path, count: int) -> None:
    rng = np.random.default_rng(1)
    signing = mavlink.MAVLink(None, srcSystem=9, srcComponent=1)
    signing.signing.secret_key = bytes(range(32))
    signing.signing.sign_outgoing = True
    with path.open("wb") as fh:
        for k in range(count):
            mav = signing if k % 11 == 0 else mavlink.MAVLink(None, srcSystem=1 + k % 3,
                                                               srcComponent=1)
            msg = _message(k % len(_NAMES), k, rng)
            v1 = k % 7 == 0 and mav is not signing and msg.id < 256  # MAVLink 1 ids are a byte
            frame = msg.pack(mav, force_mavlink1=v1)
            fh.write(struct.pack(">Q", int((1.7e9 + k * 0.01) * 1e6)) + frame)


def _same(expected: object, got: np.ndarray | np.generic) -> bool:
    if isinstance(expected, str | bytes):
        text = expected.encode() if isinstance(expected, str) else expected
        return text.rstrip(b"\0") == bytes(got).rstrip(b"\0")
    return bool(np.array_equal(np.asarray(expected, dtype=float).astype(np.float32),
                               np.asarray(got, dtype=float).astype(np.float32)))


@pytest.mark.parametrize("name", _NAMES)
def test_columns_match_pymavlink_for_v1_v2_trimmed_and_signed_frames(tmp_path: Path,
                                                                       name: str) -> None:
    path = tmp_path / "mixed.tlog"
    _write_log(path, 2 * CHUNK + 500)  # more than one chunk of each of several types
    index = TlogIndex.build(path)
    records = index.select(name)
    columns = decode_columns(path, index.offset, records, name)
    messages = [m for _, m in index.messages(records)]
    assert len(messages) == len(columns) == len(records) > 0
    for msg, row in zip(messages, columns, strict=True):
        for field in columns.dtype.names:
            assert _same(getattr(msg, field), row[field]), (name, field)


def test_wire_dtype_is_the_struct_layout() -> None:
    cls = mavlink.MAVLink_debug_float_array_message
    dtype = wire_dtype(cls)
    assert dtype.names == tuple(cls.ordered_fieldnames)
    assert dtype["data"].shape == (58,) and dtype["name"].itemsize == 10
    assert dtype.itemsize == cls.unpacker.size


def test_no_records_and_unknown_names(tmp_path: Path) -> None:
    path = tmp_path / "small.tlog"
    _write_log(path, 10)
    index = TlogIndex.build(path)
    assert len(decode_columns(path, index.offset, np.zeros(0, dtype=int), "ATTITUDE")) == 0
    with pytest.raises(ValueError, match="unknown MAVLink message 'NO_SUCH'"):
        decode_columns(path, index.offset, np.zeros(0, dtype=int), "NO_SUCH")
