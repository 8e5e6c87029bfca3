"""Flight recorder: every MAVLink frame in and out, plus the GCS's own internals, as a .tlog.

The file is a plain telemetry log as MAVProxy and QGroundControl write it: each
record is an 8-byte big-endian timestamp (microseconds since the Unix epoch)
followed by one raw MAVLink frame, so ``pymavlink.mavutil`` and
``mavlogdump.py`` read it as they are. The GCS's internals travel as standard
messages from the GCS's own system id:

* ``DEBUG_FLOAT_ARRAY`` per tick, named and numbered as in :data:`ARRAYS`:
  ``dist_err`` distance error per edge (m), ``acc_cmd`` commanded NED
  acceleration x, y per vehicle (m/s^2), ``tilt`` per vehicle (rad); in
  simulation also the truth: ``payload`` (p_ned, v_ned), ``rope_T`` tension per
  rope (N), ``veh_true`` true vehicle positions (x, y, z per vehicle). Arrays
  longer than 58 values continue in the next array_id;
* ``NAMED_VALUE_FLOAT`` ``stk_fwd``, ``stk_rgt``, ``stk_rot``, ``scale``,
  ``alt_tgt``: the operator command; ``NAMED_VALUE_INT`` ``phase``;
* ``DEBUG_FLOAT_ARRAY`` ``team`` once at the start (see :func:`team_header`): the
  vehicle ids, edges, desired distances and acceleration limits, so a log
  explains itself without its config;
* ``STATUSTEXT`` for phase changes and safety warnings (what replay jumps to).

Timestamps follow the loop's clock (``epoch + t``), so a flight run faster than
real time replays on its own time line. Data is flushed at least every
``flush_interval`` seconds of wall time: a killed GCS loses at most that, and a
truncated file still reads up to its last whole record.
"""

from __future__ import annotations

import struct
import threading
import time
from pathlib import Path
from typing import TypedDict

import numpy as np

from gcs.wire import MavlinkEncoder, MavMessage, mavlink

__all__ = ["ARRAYS", "ARRAY_SPAN", "TeamHeader", "TlogRecorder", "chunked",
           "parse_team_header", "team_header"]

#: First DEBUG_FLOAT_ARRAY array_id of each recorded array; each owns ARRAY_SPAN ids.
ARRAYS = {"dist_err": 1, "acc_cmd": 101, "tilt": 301, "payload": 201, "rope_T": 211,
          "veh_true": 221, "team": 401, "alt_trim": 501}
ARRAY_SPAN = 10
_ARRAY_LEN = 58
_STAMP = struct.Struct(">Q")


def chunked(values: np.ndarray) -> list[np.ndarray]:
    """Split a flat array into DEBUG_FLOAT_ARRAY-sized pieces (58 floats each)."""
    flat = np.asarray(values, dtype=float).ravel()
    return [flat[i : i + _ARRAY_LEN] for i in range(0, max(len(flat), 1), _ARRAY_LEN)]


def team_header(ids: tuple[int, ...], edges: np.ndarray, distances: np.ndarray,
                accel_norm: float, accel_axis: float) -> np.ndarray:
    """[n, m, ids.., tail ids.., head ids.., d.., accel_norm, accel_axis] as one array."""
    tails = [ids[i] for i in edges[:, 0]]
    heads = [ids[j] for j in edges[:, 1]]
    return np.array([len(ids), len(edges), *ids, *tails, *heads, *distances, accel_norm,
                     accel_axis], dtype=float)


class TeamHeader(TypedDict):
    """The team as :func:`parse_team_header` reads it back from a log."""

    ids: tuple[int, ...]
    edges: np.ndarray  # (m, 2) indices into ids: tail, head
    distances: np.ndarray  # (m,) desired distances, m
    accel_norm: float
    accel_axis: float


def parse_team_header(values: np.ndarray) -> TeamHeader:
    """Inverse of :func:`team_header`; ValueError if the array is not one."""
    try:
        n, m = int(values[0]), int(values[1])
        ids = tuple(int(v) for v in values[2 : 2 + n])
        tails = [int(v) for v in values[2 + n : 2 + n + m]]
        heads = [int(v) for v in values[2 + n + m : 2 + n + 2 * m]]
        d = np.asarray(values[2 + n + 2 * m : 2 + n + 3 * m], dtype=float)
        norm, axis = float(values[2 + n + 3 * m]), float(values[3 + n + 3 * m])
    except (IndexError, ValueError) as exc:
        raise ValueError(f"not a team header: {exc}") from None
    index = {vid: i for i, vid in enumerate(ids)}
    edges = np.array([[index[a], index[b]] for a, b in zip(tails, heads, strict=True)])
    return {"ids": ids, "edges": edges, "distances": d, "accel_norm": norm,
            "accel_axis": axis}


class TlogRecorder:
    """Append-only .tlog writer; thread-safe (link threads and the loop write).

    Args:
        path: the file to create (parent folders are made).
        encoder: the GCS's own encoder, for the internals it records.
        epoch: Unix time of the clock's zero, s.
        flush_interval: longest wall time between flushes, s.
    """

    def __init__(self, path: str | Path, *, encoder: MavlinkEncoder, epoch: float,
                 flush_interval: float = 0.5) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = self.path.open("wb")
        self._enc = encoder
        self._epoch = epoch
        self._flush_interval = flush_interval
        self._last_flush = time.monotonic()
        self._lock = threading.Lock()
        self._boot = 0.0
        self.records = 0
        self.errors = 0
        """Write failures (disk full...): counted, never raised into the loop."""

    def frame(self, t: float, frame: bytes) -> None:
        """Record one raw MAVLink frame seen (in or out) at loop time ``t``."""
        with self._lock:
            if self._file.closed:
                return
            try:
                self._file.write(_STAMP.pack(round((self._epoch + t) * 1e6)) + frame)
                self.records += 1
                now = time.monotonic()
                if now - self._last_flush >= self._flush_interval:
                    self._file.flush()
                    self._last_flush = now
            except OSError:
                self.errors += 1

    def message(self, t: float, msg: MavMessage) -> None:
        """Encode one of the GCS's own messages and record it."""
        self.frame(t, self._enc.encode(msg))

    def internals(self, t: float, *, arrays: dict[str, np.ndarray],
                  sticks: tuple[float, float, float], scale: float, altitude: float,
                  phase: int) -> None:
        """Record one tick of guidance internals (``arrays`` named as in ARRAYS)."""
        mav = self._enc.mav
        ms = round(t * 1e3) & 0xFFFFFFFF
        for name, values in arrays.items():
            self.array(t, name, values)
        for key, value in ((b"stk_fwd", sticks[0]), (b"stk_rgt", sticks[1]),
                           (b"stk_rot", sticks[2]), (b"scale", scale),
                           (b"alt_tgt", altitude)):
            self.message(t, mav.named_value_float_encode(ms, key, float(value)))
        self.message(t, mav.named_value_int_encode(ms, b"phase", int(phase)))

    def team(self, t: float, *, ids: tuple[int, ...], edges: np.ndarray, distances: np.ndarray,
             accel_norm: float, accel_axis: float) -> None:
        """Record the team (ids, edges, desired distances, limits) that replay and reports read."""
        self.array(t, "team", team_header(ids, edges, distances, accel_norm, accel_axis))

    def array(self, t: float, name: str, values: np.ndarray) -> None:
        """Record one named array (see ARRAYS), split over as many messages as it needs."""
        usec = round(t * 1e6)
        for k, part in enumerate(chunked(values)):
            data = np.zeros(_ARRAY_LEN)
            data[: len(part)] = part
            self.message(t, self._enc.mav.debug_float_array_encode(
                usec, name.encode(), ARRAYS[name] + k, data.tolist()))

    def text(self, t: float, text: str, *, severity: int = mavlink.MAV_SEVERITY_INFO) -> None:
        """Record a STATUSTEXT (phase changes, warnings); long texts are cut at 50 bytes."""
        raw = text.encode("utf-8", "replace")[:50]
        self.message(t, self._enc.mav.statustext_encode(severity, raw))

    def flush(self) -> None:
        """Push everything written so far to the operating system."""
        with self._lock:
            if not self._file.closed:
                self._file.flush()
                self._last_flush = time.monotonic()

    def close(self) -> None:
        """Flush and close; later writes are ignored."""
        with self._lock:
            if not self._file.closed:
                self._file.flush()
                self._file.close()
