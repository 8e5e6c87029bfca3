"""The compiled log scan finds exactly the checked records, across chunks and damage."""

from __future__ import annotations

import struct

import numpy as np

from gcs.flightlog._scan import CRC_EXTRA, SCAN_FIELDS, scan_buffer, scan_records
from gcs.wire import mavlink

_T0_US = 1_700_000_000_000_000


def _frame(k: int, *, v1: bool = False, sysid: int = 1, compid: int = 1) -> bytes:
    mav = mavlink.MAVLink(None, srcSystem=sysid, srcComponent=compid)
    mav.seq = k % 256
    return mavlink.MAVLink_local_position_ned_message(k, k, -k, 1.5, 0, 0, 0).pack(
        mav, force_mavlink1=v1)


def _record(k: int, frame: bytes) -> bytes:
    return struct.pack(">Q", _T0_US + 10_000 * k) + frame


def _log(count: int) -> tuple[bytes, list[int]]:
    """``count`` records from two components, every fifth MAVLink 1; frame offsets."""
    out, offsets = bytearray(), []
    for k in range(count):
        offsets.append(len(out) + 8)
        out += _record(k, _frame(k, v1=k % 5 == 0, compid=1 + k % 2))
    return bytes(out), offsets


def _scan(data: bytes):
    return scan_buffer(np.frombuffer(data, dtype=np.uint8))


def test_every_record_is_found_with_its_fields() -> None:
    data, offsets = _log(300)
    scan = _scan(data)
    c = scan.columns
    assert list(c["offset"]) == offsets
    assert list(c["t_us"]) == [_T0_US + 10_000 * k for k in range(300)]
    assert set(c["msgid"]) == {mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED}
    assert list(c["seq"]) == [k % 256 for k in range(300)]
    assert list(c["compid"]) == [1 + k % 2 for k in range(300)]
    assert (c["sysid"] == 1).all()
    assert scan.skipped_bytes == 0 and scan.unknown_frames == 0 and not scan.truncated


def test_a_frame_with_a_bad_checksum_is_skipped_not_indexed() -> None:
    data, offsets = _log(20)
    broken = bytearray(data)
    broken[offsets[7] + 12] ^= 0xFF  # a payload byte of record 7: its checksum fails
    scan = _scan(bytes(broken))
    assert list(scan.columns["offset"]) == offsets[:7] + offsets[8:]
    assert scan.skipped_bytes == offsets[8] - 8 - (offsets[7] - 8)  # the whole record


def test_unknown_types_are_stepped_over_and_counted() -> None:
    data, _ = _log(6)
    frame = bytearray(_frame(99))
    frame[7:10] = (0xFFFFFF).to_bytes(3, "little")  # an id this dialect does not know
    assert CRC_EXTRA.shape[0] <= 0xFFFFFF
    record = _record(99, bytes(frame))
    scan = _scan(data + record + data)
    assert len(scan.columns["t_us"]) == 12
    assert scan.unknown_frames == 1 and scan.skipped_bytes == 0


def test_garbage_and_a_truncated_tail() -> None:
    data, _ = _log(10)
    garbage = bytes(np.random.default_rng(3).integers(0, 256, 5000, dtype=np.uint8))
    scan = _scan(data + garbage + data + data[:40])  # record 0 (MAVLink 1) is 44 bytes
    assert len(scan.columns["t_us"]) == 20
    assert scan.skipped_bytes >= 4900 and scan.truncated


def test_resuming_at_every_chunk_boundary_gives_the_same_records() -> None:
    data, offsets = _log(50)
    buf = np.frombuffer(data, dtype=np.uint8)
    dtypes = [c.dtype for c in _scan(data).columns.values()]
    pos, found = 0, []
    while pos + 8 < len(buf):
        cols = [np.empty(3, dtype=d) for d in dtypes]
        n, pos, _, _, _ = scan_records(buf, pos, CRC_EXTRA, *cols)
        found += list(cols[SCAN_FIELDS.index("offset")][:n])
    assert found == offsets


def test_an_empty_buffer() -> None:
    scan = _scan(b"")
    assert all(len(c) == 0 for c in scan.columns.values())
    assert not scan.truncated
