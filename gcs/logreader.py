"""Random access to .tlog files of any length: index once, decode only what is asked.

One pass over the file (memory-mapped) records, per record, its timestamp,
offset, length, message id, system id and sequence number in compact numpy
arrays (about 30 bytes a message), without decoding any payload. Replay and
reports then decode only the messages of the types and the time window they
need. Corrupt stretches are skipped by resynchronising on the next plausible
record and counted; a truncated tail is reported, never fatal.
"""

from __future__ import annotations

import mmap
import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gcs.link.dialect import MavMessage, mavlink

__all__ = ["LogError", "TlogIndex"]

_STAMP = struct.Struct(">Q")
_V2, _V1 = 0xFD, 0xFE
#: Timestamps outside [2000, 2100) are not timestamps: the reader is out of step.
_T_MIN, _T_MAX = 946_684_800_000_000, 4_102_444_800_000_000


class LogError(ValueError):
    """A file that holds no readable MAVLink log."""


@dataclass(frozen=True, eq=False)
class TlogIndex:
    """Where every message of a .tlog is; build with :meth:`build`."""

    path: Path
    t: np.ndarray  # (N,) float64 Unix time, s
    offset: np.ndarray  # (N,) int64 offset of the frame (after its timestamp)
    length: np.ndarray  # (N,) int32 frame length
    msgid: np.ndarray  # (N,) int32
    sysid: np.ndarray  # (N,) int16
    seq: np.ndarray  # (N,) int16
    skipped_bytes: int
    truncated: bool

    @classmethod
    def build(cls, path: str | Path,
              progress: Callable[[int, int], None] | None = None) -> TlogIndex:
        """Index ``path``; ``progress(done_bytes, total_bytes)`` is called now and then."""
        path = Path(path)
        try:
            size = path.stat().st_size
        except OSError as exc:
            raise LogError(f"{path}: cannot read file ({exc.strerror})") from None
        if size == 0:
            raise LogError(f"{path}: empty file: no MAVLink messages")
        cols: dict[str, list[int]] = {k: [] for k in ("t", "off", "len", "id", "sys", "seq")}
        skipped = 0
        truncated = False
        with path.open("rb") as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as mm:
            pos = 0
            next_report = 0
            while pos + 8 < size:
                if progress is not None and pos >= next_report:
                    progress(pos, size)
                    next_report = pos + (1 << 20)
                stamp = _STAMP.unpack_from(mm, pos)[0]
                frame_len = _frame_length(mm, pos + 8, size)
                if frame_len is None or not _T_MIN <= stamp < _T_MAX:
                    pos += 1
                    skipped += 1
                    continue
                if frame_len < 0:  # runs past the end of the file
                    truncated = True
                    break
                start = pos + 8
                v2 = mm[start] == _V2
                cols["t"].append(stamp)
                cols["off"].append(start)
                cols["len"].append(frame_len)
                if v2:
                    cols["id"].append(mm[start + 7] | mm[start + 8] << 8 | mm[start + 9] << 16)
                    cols["sys"].append(mm[start + 5])
                    cols["seq"].append(mm[start + 4])
                else:
                    cols["id"].append(mm[start + 5])
                    cols["sys"].append(mm[start + 3])
                    cols["seq"].append(mm[start + 2])
                pos = start + frame_len
            truncated = truncated or 0 < size - pos <= 8  # a timestamp with no frame
        if progress is not None:
            progress(size, size)
        if not cols["t"]:
            raise LogError(f"{path}: no MAVLink messages found ({size} bytes)")
        return cls(path=path, t=np.array(cols["t"], dtype=np.float64) * 1e-6,
                   offset=np.array(cols["off"], dtype=np.int64),
                   length=np.array(cols["len"], dtype=np.int32),
                   msgid=np.array(cols["id"], dtype=np.int32),
                   sysid=np.array(cols["sys"], dtype=np.int16),
                   seq=np.array(cols["seq"], dtype=np.int16), skipped_bytes=skipped,
                   truncated=truncated)

    def __len__(self) -> int:
        return len(self.t)

    def select(self, name: str, *, sysid: int | None = None) -> np.ndarray:
        """Record numbers of every message called ``name`` (from ``sysid`` if given)."""
        mask = self.msgid == _msg_id(name)
        if sysid is not None:
            mask &= self.sysid == sysid
        return np.flatnonzero(mask)

    def systems(self) -> list[int]:
        """System ids that sent anything, ascending."""
        return sorted(int(s) for s in np.unique(self.sysid))

    def messages(self, records: np.ndarray) -> Iterator[tuple[float, MavMessage]]:
        """Decode the given records, in order, as (Unix time, message); bad ones skipped."""
        parser = mavlink.MAVLink(None)
        parser.robust_parsing = True
        with self.path.open("rb") as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as mm:
            for r in records:
                start = int(self.offset[r])
                frame = bytes(mm[start : start + int(self.length[r])])
                try:
                    msg = parser.decode(bytearray(frame))
                except Exception:  # pymavlink raises its own base exception for bad CRCs
                    continue
                yield float(self.t[r]), msg

    def packets_lost(self, sysid: int) -> int:
        """Frames missing from ``sysid``'s sequence numbers (first component seen)."""
        recs = np.flatnonzero(self.sysid == sysid)
        if len(recs) < 2:
            return 0
        seq = self.seq[recs].astype(np.int64)
        gaps = (np.diff(seq) - 1) % 256
        return int(gaps[gaps < 128].sum())  # a huge "gap" is a reordering or a restart


def _msg_id(name: str) -> int:
    value = getattr(mavlink, f"MAVLINK_MSG_ID_{name.upper()}", None)
    if not isinstance(value, int):
        raise ValueError(f"unknown MAVLink message {name!r}")
    return value


def _frame_length(mm: mmap.mmap, start: int, size: int) -> int | None:
    """Length of the frame at ``start``; None if no frame starts there, -1 if cut short."""
    if start + 3 > size:
        return -1
    magic = mm[start]
    if magic == _V2:
        length = 10 + mm[start + 1] + 2 + (13 if mm[start + 2] & 0x01 else 0)
    elif magic == _V1:
        length = 6 + mm[start + 1] + 2
    else:
        return None
    return length if start + length <= size else -1
