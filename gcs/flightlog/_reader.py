"""Random access to .tlog files of any length: index once, decode only what is asked.

One compiled pass over the file (memory-mapped, :mod:`gcs.flightlog._scan`) records,
per record, its timestamp, offset, length, message id, system id, component id
and sequence number in numpy columns (about 30 bytes a message), without
decoding any payload. Replay and reports then decode only the messages of the
types and the time window they need.

Only frames whose checksum (with their type's CRC_EXTRA) holds enter the
index, so a corrupt stretch never invents systems or messages: where no
checked record starts, the reader moves on by one byte and counts it as
skipped; a frame of a type the dialect does not know cannot be checked and is
stepped over whole and counted. The recorder's timestamps are not
checksummed: a record whose time jumps far from its neighbours' is a damaged
stamp, rejected and counted. A truncated tail is reported, never fatal.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gcs.flightlog._scan import map_file, scan_buffer
from gcs.wire import MavMessage, mavlink, message_id

__all__ = ["LogError", "TlogIndex"]

#: A record more than this away from its neighbours' times has a damaged stamp, s.
TIME_JUMP_S = 2.0
_NEIGHBOURS = 4  # records each side whose median time a suspect record is judged by


class LogError(ValueError):
    """A file that holds no readable MAVLink log."""


@dataclass(frozen=True, eq=False)
class TlogIndex:
    """Where every message of a .tlog is; build with :meth:`build`."""

    path: Path
    t: np.ndarray  # (N,) float64 Unix time, s
    offset: np.ndarray  # (N,) int64 offset of the frame (after its timestamp)
    length: np.ndarray  # (N,) uint16 frame length
    msgid: np.ndarray  # (N,) int32
    sysid: np.ndarray  # (N,) uint8
    compid: np.ndarray  # (N,) uint8
    seq: np.ndarray  # (N,) uint8
    skipped_bytes: int
    truncated: bool
    unknown_frames: int = 0  # frames of message types the dialect does not know
    rejected_times: int = 0  # checked frames dropped for a damaged timestamp

    @classmethod
    def build(cls, path: str | Path,
              progress: Callable[[int, int], None] | None = None) -> TlogIndex:
        """Index ``path``; ``progress(done_bytes, total_bytes)`` is called now and then."""
        path = Path(path)
        try:
            size = path.stat().st_size
            if size == 0:
                raise LogError(f"{path}: empty file: no MAVLink messages")
            scan = scan_buffer(map_file(path), progress)
        except OSError as exc:
            raise LogError(f"{path}: cannot read file ({exc.strerror or exc})") from None
        if progress is not None:
            progress(size, size)
        cols = scan.columns
        keep = ~_time_jumps(cols["t_us"] * 1e-6)
        if not keep.any():
            raise LogError(f"{path}: no MAVLink messages found ({size} bytes)")
        if not keep.all():
            cols = {k: v[keep] for k, v in cols.items()}
        return cls(path=path, t=cols["t_us"] * 1e-6, offset=cols["offset"],
                   length=cols["length"], msgid=cols["msgid"], sysid=cols["sysid"],
                   compid=cols["compid"], seq=cols["seq"], skipped_bytes=scan.skipped_bytes,
                   truncated=scan.truncated, unknown_frames=scan.unknown_frames,
                   rejected_times=int(len(keep) - keep.sum()))

    def __len__(self) -> int:
        return len(self.t)

    def damage(self) -> str | None:
        """What could not be read, in one line (None for a log read whole).

        One wording for every command that opens a log (``gcs report`` prints it,
        ``gcs replay`` prints it and shows it on the page), so a damaged log is
        described the same way wherever it is opened.
        """
        if not (self.truncated or self.skipped_bytes or self.unknown_frames
                or self.rejected_times):
            return None
        return (f"truncated={self.truncated}, corrupt bytes skipped={self.skipped_bytes}, "
                f"unknown frames skipped={self.unknown_frames}, "
                f"records with a damaged timestamp rejected={self.rejected_times}")

    def select(self, name: str, *, sysid: int | None = None) -> np.ndarray:
        """Record numbers of every message called ``name`` (from ``sysid`` if given)."""
        mask = self.msgid == message_id(name)
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
        buf = map_file(self.path)
        for r in records:
            start = int(self.offset[r])
            frame = bytearray(buf[start : start + int(self.length[r])])
            try:
                msg = parser.decode(frame)
            except Exception:  # pymavlink raises its own base exception for bad CRCs
                continue
            yield float(self.t[r]), msg

    def streams_lost(self, systems: Iterable[int]) -> dict[tuple[int, int], int]:
        """Frames missing from the sequence numbers of each (system, component) of ``systems``.

        Every component numbers its frames on its own, so a gimbal beside an
        autopilot is a second stream, not a jump in the first. A "gap" of more
        than half the counter is a reordering or a restart, not a loss.
        """
        recs = np.flatnonzero(np.isin(self.sysid, list(systems)))
        stream = self.sysid[recs].astype(np.int64) << 8 | self.compid[recs]
        order = np.argsort(stream, kind="stable")  # each stream's frames in file order
        stream, seq = stream[order], self.seq[recs][order].astype(np.int64)
        gaps = (np.diff(seq) - 1) % 256
        gaps[(np.diff(stream) != 0) | (gaps >= 128)] = 0  # a gap belongs to its later frame
        keys, group = np.unique(stream, return_inverse=True)
        lost = np.bincount(group[1:], weights=gaps, minlength=len(keys))
        return {(int(k) >> 8, int(k) & 0xFF): int(n) for k, n in zip(keys, lost, strict=True)}


def _time_jumps(t: np.ndarray) -> np.ndarray:
    """Records whose time is damaged: far from both neighbours and from their median.

    A real gap in a log (a pause) has neighbours on both sides that agree with
    one record or the other, and within a run of records the median of the
    neighbours is the record's own time; a stamp with a flipped high byte is
    far from all of them. Only suspects (far from both neighbours) are judged.
    """
    bad = np.zeros(len(t), dtype=bool)
    if len(t) < 3:
        return bad
    step = np.abs(np.diff(t)) > TIME_JUMP_S
    suspects = np.flatnonzero(np.r_[step[0], step[:-1] & step[1:], step[-1]])
    for k in suspects:
        around = np.r_[t[max(k - _NEIGHBOURS, 0) : k], t[k + 1 : k + 1 + _NEIGHBOURS]]
        bad[k] = abs(t[k] - np.median(around)) > TIME_JUMP_S
    return bad
