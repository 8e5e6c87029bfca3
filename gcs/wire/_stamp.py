"""Many packed MAVLink 2 frames numbered and checksummed in one compiled pass.

Why: the loop sends one setpoint to every vehicle per tick and re-sends it
between ticks. Finishing a hundred frames one by one in Python (header bytes,
checksum, slicing) costs the loop more than the zenoh publication itself; one
compiled pass for the whole fleet costs a small part of that (figures:
docs/performance.md, bench/gcs_tick.py).
The CRC is MAVLink's CRC-16/MCRF4XX (X.25), as :func:`gcs.wire._crc.frame_crc`.
"""

from __future__ import annotations

import numpy as np

from gcs.common import kernel
from gcs.wire._unpack import HEADER_V2

__all__ = ["crc_accumulate", "stamp_frames"]


@kernel()
def crc_accumulate(byte: int, crc: int) -> int:
    """One byte into MAVLink's running CRC-16/MCRF4XX (X.25), for compiled callers."""
    tmp = (byte ^ crc) & 0xFF
    tmp = (tmp ^ (tmp << 4)) & 0xFF
    return ((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4)) & 0xFFFF


@kernel()
def stamp_frames(packed: np.ndarray, rows: np.ndarray, counters: np.ndarray, sysid: np.ndarray,
                 compid: np.ndarray, signed: np.ndarray, crc_extra: int,
                 out: np.ndarray) -> np.ndarray:
    """Finish row ``k`` of ``packed`` into a frame of sender ``rows[k]`` in row ``k`` of
    ``out``; the frame lengths.

    ``packed`` (m, size) uint8: a MAVLink 2 header (marker and message id set)
    and the full payload, as :func:`gcs.wire._encoder.packed_rows` builds.
    Senders ``i`` are rows of ``counters`` (n, 2) int64 (sequence number, frames
    sent), ``sysid`` and ``compid`` (n,) uint8 and ``signed`` (n,) bool. Per
    frame: the payload's trailing zeros dropped (MAVLink 2), length, sender's
    sequence number and ids written, no incompatibility flags, checksum with
    ``crc_extra`` appended; the sender's counters advance. Rows of signed
    senders are left alone (length 0): the caller signs those one by one.
    ``out`` is (m, size + 2 or more) uint8.
    """
    m, size = packed.shape
    lengths = np.zeros(m, np.int64)
    for k in range(m):
        i = rows[k]
        if signed[i]:
            continue
        payload = size - HEADER_V2
        while payload > 1 and packed[k, HEADER_V2 + payload - 1] == 0:
            payload -= 1
        end = HEADER_V2 + payload
        out[k, 0] = packed[k, 0]
        out[k, 1] = payload
        out[k, 2] = 0
        out[k, 3] = 0
        out[k, 4] = counters[i, 0]
        out[k, 5] = sysid[i]
        out[k, 6] = compid[i]
        crc = 0xFFFF
        for j in range(1, 7):
            crc = crc_accumulate(out[k, j], crc)
        for j in range(7, end):
            out[k, j] = packed[k, j]
            crc = crc_accumulate(packed[k, j], crc)
        crc = crc_accumulate(crc_extra, crc)
        out[k, end] = crc & 0xFF
        out[k, end + 1] = crc >> 8
        lengths[k] = end + 2
        counters[i, 0] = (counters[i, 0] + 1) & 0xFF
        counters[i, 1] += 1
    return lengths
