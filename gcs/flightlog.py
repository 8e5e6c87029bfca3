"""A recorded flight read back as arrays: guidance ticks, vehicle tracks, events.

Works on logs written by the GCS's recorder (with guidance internals, team
header and, in simulation, ground truth) and on plain telemetry logs of real
autopilots (then only the vehicle tracks and texts exist; ``missing`` says what
is absent). Only the message types used are decoded, through the index.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gcs.logreader import TlogIndex
from gcs.metrics import FlightMetrics
from gcs.phases import Phase
from gcs.recorder import ARRAY_SPAN, ARRAYS, parse_team_header

__all__ = ["FlightLog", "Track"]

_ARRAY_OF = {base + k: name for name, base in ARRAYS.items() for k in range(ARRAY_SPAN)}


@dataclass(frozen=True, eq=False)
class Track:
    """One vehicle's telemetry: times (Unix s) and NED states."""

    t: np.ndarray
    p_ned: np.ndarray  # (K, 3)
    v_ned: np.ndarray  # (K, 3)
    att_t: np.ndarray
    rpy: np.ndarray  # (J, 3)


@dataclass(eq=False)
class FlightLog:
    """Everything a replay or a report needs from one .tlog."""

    index: TlogIndex
    gcs_sysid: int | None
    team: dict[str, object] | None
    tick_t: np.ndarray  # (K,) Unix s
    phase: np.ndarray  # (K,) int
    values: dict[str, np.ndarray]  # NAMED_VALUE_FLOAT per tick: stk_fwd, scale, alt_tgt...
    arrays: dict[str, np.ndarray]  # per tick: dist_err (K, m), acc_cmd (K, 2n), tilt...
    tracks: dict[int, Track]
    texts: list[tuple[float, int, int, str]]  # (t, sysid, severity, text)
    missing: list[str] = field(default_factory=list)

    @classmethod
    def load(cls, path: str | Path,
             progress: Callable[[str, int, int], None] | None = None) -> FlightLog:
        """Read ``path``; LogError if it holds no MAVLink at all."""
        index = TlogIndex.build(path, progress=(lambda d, n: progress("index", d, n))
                                if progress else None)
        gcs_sysid = _gcs_system(index)
        ticks: dict[int, dict[str, object]] = defaultdict(dict)
        team = None
        if gcs_sysid is not None:
            team = _read_internals(index, gcs_sysid, ticks, progress)
        tracks = {sysid: _read_track(index, sysid) for sysid in index.systems()
                  if sysid != gcs_sysid and len(index.select("LOCAL_POSITION_NED",
                                                             sysid=sysid))}
        texts = [(t, int(m.get_srcSystem()), int(m.severity), str(m.text))
                 for t, m in index.messages(index.select("STATUSTEXT"))]
        log = cls(index=index, gcs_sysid=gcs_sysid, team=team, tick_t=np.zeros(0),
                  phase=np.zeros(0, dtype=int), values={}, arrays={}, tracks=tracks,
                  texts=texts)
        log._assemble(ticks)
        return log

    def _assemble(self, ticks: dict[int, dict[str, object]]) -> None:
        whole = [u for u in sorted(ticks) if "phase" in ticks[u]]
        self.tick_t = np.array([ticks[u]["t"] for u in whole], dtype=float)
        self.phase = np.array([ticks[u]["phase"] for u in whole], dtype=int)
        names = {k for u in whole for k in ticks[u] if k not in ("t", "phase")}
        for name in sorted(names):
            rows = [ticks[u].get(name) for u in whole]
            if name in ARRAYS:
                width = max(len(r) for r in rows if r is not None)  # type: ignore[arg-type]
                out = np.full((len(rows), width), np.nan)
                for k, r in enumerate(rows):
                    if r is not None:
                        out[k, : len(r)] = r  # type: ignore[arg-type]
                self.arrays[name] = out
            else:
                self.values[name] = np.array([np.nan if r is None else r for r in rows],
                                             dtype=float)
        if self.gcs_sysid is None:
            self.missing.append("guidance internals (no GCS messages: a plain autopilot log)")
        if self.team is None:
            self.missing.append("team header (edges and desired distances)")
        if "payload" not in self.arrays:
            self.missing.append("payload and rope truth (only recorded in simulation)")
        if not self.tracks:
            self.missing.append("vehicle positions (no LOCAL_POSITION_NED)")

    @property
    def n_vehicles(self) -> int:
        if self.team is not None:
            return len(self.team["ids"])  # type: ignore[arg-type]
        return len(self.tracks)

    def metrics(self) -> FlightMetrics:
        """The flight metrics, computed exactly as ``gcs fly`` computes them live."""
        m = FlightMetrics()
        n = self.n_vehicles
        has_truth = all(k in self.arrays for k in ("payload", "rope_T", "veh_true"))
        for k, t in enumerate(self.tick_t):
            de = self.arrays.get("dist_err")
            acc = self.arrays.get("acc_cmd")
            tilt = self.arrays.get("tilt")
            m.add_tick(
                t - self.tick_t[0], Phase(int(self.phase[k])),
                distance_errors=de[k] if de is not None else np.array([np.nan]),
                tilt=tilt[k, :n] if tilt is not None else np.full(n, np.nan),
                accel_cmd=acc[k, : 2 * n].reshape(n, 2) if acc is not None else np.zeros((1, 2)),
                vehicles_true=self.arrays["veh_true"][k, : 3 * n].reshape(n, 3)
                if has_truth else None,
                payload=self.arrays["payload"][k, :3] if has_truth else None,
                rope_tension=self.arrays["rope_T"][k, :n] if has_truth else None)
        return m

    def phase_changes(self) -> list[tuple[float, str]]:
        """(time, phase name) at each change of phase."""
        out = []
        for k in range(len(self.phase)):
            if k == 0 or self.phase[k] != self.phase[k - 1]:
                out.append((float(self.tick_t[k]), Phase(int(self.phase[k])).text))
        return out


def _gcs_system(index: TlogIndex) -> int | None:
    """The system that wrote guidance internals (the recorder's GCS), if any."""
    recs = index.select("NAMED_VALUE_INT")
    if not len(recs):
        return None
    return int(np.bincount(index.sysid[recs].astype(int)).argmax())


def _read_internals(index: TlogIndex, gcs: int, ticks: dict[int, dict[str, object]],
                    progress: Callable[[str, int, int], None] | None) -> dict | None:
    recs = np.sort(np.concatenate([index.select(name, sysid=gcs) for name in
                                   ("DEBUG_FLOAT_ARRAY", "NAMED_VALUE_FLOAT",
                                    "NAMED_VALUE_INT")]))
    team = None
    parts: dict[tuple[int, str], dict[int, list[float]]] = defaultdict(dict)
    for k, (t, msg) in enumerate(index.messages(recs)):
        if progress is not None and k % 20000 == 0:
            progress("decode", k, len(recs))
        stamp = round(t * 1e6)  # one tick's messages share the recorder's time stamp
        if msg.get_type() == "DEBUG_FLOAT_ARRAY":
            name = _ARRAY_OF.get(int(msg.array_id))
            if name is not None:
                parts[(stamp, name)][int(msg.array_id) - ARRAYS[name]] = list(msg.data)
        else:
            tick = ticks[stamp]
            tick["t"] = t
            tick[str(msg.name)] = msg.value
    for (stamp, name), chunks in parts.items():
        flat = np.concatenate([chunks[i] for i in sorted(chunks)])
        if name == "team":
            if team is None:
                try:
                    team = parse_team_header(flat)
                except ValueError:
                    team = None
            continue
        if stamp in ticks:
            ticks[stamp][name] = _trim(name, flat, team)
    return team


def _trim(name: str, flat: np.ndarray, team: dict | None) -> np.ndarray:
    """Cut the zero padding of the last DEBUG_FLOAT_ARRAY chunk when sizes are known."""
    if team is None:
        return flat
    n = len(team["ids"])
    m = len(team["distances"])
    size = {"dist_err": m, "acc_cmd": 2 * n, "tilt": n, "payload": 6, "rope_T": n,
            "veh_true": 3 * n}.get(name)
    return flat[:size] if size is not None else flat


def _read_track(index: TlogIndex, sysid: int) -> Track:
    pos = [(t, m) for t, m in index.messages(index.select("LOCAL_POSITION_NED", sysid=sysid))]
    att = [(t, m) for t, m in index.messages(index.select("ATTITUDE", sysid=sysid))]
    return Track(t=np.array([t for t, _ in pos]),
                 p_ned=np.array([[m.x, m.y, m.z] for _, m in pos]).reshape(-1, 3),
                 v_ned=np.array([[m.vx, m.vy, m.vz] for _, m in pos]).reshape(-1, 3),
                 att_t=np.array([t for t, _ in att]),
                 rpy=np.array([[m.roll, m.pitch, m.yaw] for _, m in att]).reshape(-1, 3))
