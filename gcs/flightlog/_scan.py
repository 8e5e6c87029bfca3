"""One compiled pass over a .tlog's bytes: where each checked MAVLink frame is.

Why compiled: an indexer in Python spends interpreter work on every byte it
inspects and keeps a Python int per field per message while it builds; a log of
hours holds millions of messages (figures: docs/performance.md,
bench/log_read.py). This kernel walks the memory-mapped file once, checks each
frame's checksum with its type's CRC_EXTRA (so a corrupt stretch never invents
systems or messages), and writes the record's fields into preallocated numpy
columns, a chunk of records at a time.

A record is the recorder's 8-byte big-endian Unix time in microseconds
followed by one MAVLink 1 or 2 frame. Where no plausible record starts
(a timestamp outside [2000, 2100), no start marker, a failed checksum), the
scan moves on by one byte and counts it as skipped; a frame of a message type
this dialect does not know cannot be checked and is stepped over whole and
counted; a record that runs past the end of the file marks the log truncated.
"""

from __future__ import annotations

import mmap
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gcs.common import kernel
from gcs.wire import crc_accumulate, mavlink

__all__ = ["CHUNK_RECORDS", "CRC_EXTRA", "SCAN_FIELDS", "T_MAX_US", "T_MIN_US", "Scan",
           "map_file", "release_pages", "scan_buffer", "scan_records"]

T_MIN_US, T_MAX_US = 946_684_800_000_000, 4_102_444_800_000_000
"""Timestamps outside [2000, 2100) are not timestamps: the reader is out of step."""

CRC_EXTRA = np.full(1 << 16, -1, dtype=np.int16)
"""CRC_EXTRA per message id of the dialect, -1 where the id is unknown."""
for _msgid, _cls in mavlink.mavlink_map.items():
    if _msgid < len(CRC_EXTRA):
        CRC_EXTRA[_msgid] = _cls.crc_extra

SCAN_FIELDS = ("t_us", "offset", "length", "msgid", "sysid", "compid", "seq")
"""The columns :func:`scan_records` fills, in its argument order."""

CHUNK_RECORDS = 1 << 18
"""Records per kernel call: bounds the spare column space and paces progress reports."""

_TYPICAL_RECORD_BYTES = 40  # a timestamp and a small telemetry frame
_DONTNEED = getattr(mmap, "MADV_DONTNEED", None)
_DTYPES = (np.int64, np.int64, np.uint16, np.int32, np.uint8, np.uint8, np.uint8)
_V2, _V1 = 0xFD, 0xFE
_SIGNED = 0x01


@kernel()
def scan_records(buf: np.ndarray, pos: int, crc_extra: np.ndarray, t_us: np.ndarray,
                 offset: np.ndarray, length: np.ndarray, msgid: np.ndarray, sysid: np.ndarray,
                 compid: np.ndarray, seq: np.ndarray) -> tuple[int, int, int, int, bool]:
    """Scan ``buf`` (uint8) from ``pos`` until the columns are full or the bytes end.

    Returns (records written, position to resume at, bytes skipped, frames of
    unknown types stepped over, truncated). ``offset`` is where each frame
    starts (its marker, after the timestamp); ``length`` its whole length.
    """
    size = buf.shape[0]
    cap = t_us.shape[0]
    n = 0
    skipped = 0
    unknown = 0
    truncated = False
    while pos + 8 < size and n < cap:
        stamp = np.int64(0)
        for j in range(8):
            stamp = (stamp << 8) | np.int64(buf[pos + j])
        start = pos + 8
        if stamp < T_MIN_US or stamp >= T_MAX_US:
            pos += 1
            skipped += 1
            continue
        marker = buf[start]
        if marker != _V2 and marker != _V1:
            pos += 1
            skipped += 1
            continue
        if start + (10 if marker == _V2 else 6) > size:  # the header runs past the end
            truncated = True
            break
        payload = np.int64(buf[start + 1])
        if marker == _V2:
            header = 10
            ident = np.int64(buf[start + 7]) | (np.int64(buf[start + 8]) << 8) | (
                np.int64(buf[start + 9]) << 16)
            frame = header + payload + 2 + (13 if buf[start + 2] & _SIGNED else 0)
            sender, component, number = buf[start + 5], buf[start + 6], buf[start + 4]
        else:
            header = 6
            ident = np.int64(buf[start + 5])
            frame = header + payload + 2
            sender, component, number = buf[start + 3], buf[start + 4], buf[start + 2]
        if start + frame > size:
            truncated = True
            break
        if ident >= crc_extra.shape[0] or crc_extra[ident] < 0:
            unknown += 1
            pos = int(start + frame)
            continue
        crc = 0xFFFF
        for j in range(start + 1, start + header + payload):
            crc = crc_accumulate(buf[j], crc)
        crc = crc_accumulate(crc_extra[ident], crc)
        end = start + header + payload
        if crc != (np.int64(buf[end]) | (np.int64(buf[end + 1]) << 8)):
            pos += 1
            skipped += 1
            continue
        t_us[n] = stamp
        offset[n] = start
        length[n] = frame
        msgid[n] = ident
        sysid[n] = sender
        compid[n] = component
        seq[n] = number
        n += 1
        pos = int(start + frame)
    return n, pos, skipped, unknown, truncated


def map_file(path: Path) -> np.ndarray:
    """The bytes of ``path``, memory-mapped read-only (unmapped when the array is freed).

    The file is not read into memory: pages are read as they are touched, and
    :func:`release_pages` drops them from this process again, so reading a log
    of hours from start to end keeps about one chunk of it resident.
    """
    with path.open("rb") as fh:
        mm = mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ)
    return np.frombuffer(mm, dtype=np.uint8)


def release_pages(buf: np.ndarray) -> None:
    """Drop the pages of a :func:`map_file` array read so far from this process's memory.

    They stay in the kernel's page cache (a re-read is cheap); without this a
    scan of a 300 MB log would leave all 300 MB counted against the process.
    """
    if _DONTNEED is not None and isinstance(buf.base, mmap.mmap):
        buf.base.madvise(_DONTNEED)


@dataclass(frozen=True)
class Scan:
    """What :func:`scan_buffer` found: one column per :data:`SCAN_FIELDS` name."""

    columns: dict[str, np.ndarray]
    skipped_bytes: int
    unknown_frames: int
    truncated: bool


def scan_buffer(buf: np.ndarray,
                progress: Callable[[int, int], None] | None = None) -> Scan:
    """Every checked record of ``buf`` (a log's bytes); ``progress(done, total)`` per chunk.

    The columns are allocated once for the records the file can hold at the
    average size of a telemetry record, grown by half when that was too few,
    and shrunk in place at the end: joining per-chunk pieces instead held the
    index twice at its peak.
    """
    size = len(buf)
    capacity = max(CHUNK_RECORDS, size // _TYPICAL_RECORD_BYTES)
    cols = [np.empty(capacity, dtype=d) for d in _DTYPES]
    n = pos = skipped = unknown = 0
    truncated = False
    while pos + 8 < size and not truncated:
        if capacity - n < CHUNK_RECORDS:
            capacity = n + max(CHUNK_RECORDS, capacity // 2)
            for c in cols:
                c.resize(capacity, refcheck=False)
        views = [c[n : n + CHUNK_RECORDS] for c in cols]
        found, pos, s, u, truncated = scan_records(buf, pos, CRC_EXTRA, *views)
        del views
        n += found
        skipped += s
        unknown += u
        release_pages(buf)
        if progress is not None:
            progress(pos, size)
    truncated = truncated or 0 < size - pos <= 8  # a timestamp with no frame
    for c in cols:
        c.resize(n, refcheck=False)
    return Scan(columns=dict(zip(SCAN_FIELDS, cols, strict=True)), skipped_bytes=skipped,
                unknown_frames=unknown, truncated=truncated)
