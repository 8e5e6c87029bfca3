"""A recorded flight read back as arrays: guidance ticks, vehicle tracks, events.

Works on logs written by the GCS's recorder (with guidance internals, team
header and, in simulation, ground truth) and on plain telemetry logs of real
autopilots (then only the vehicle tracks and texts exist; ``missing`` says what
is absent). Only the message types used are decoded, through the index; the
vehicle tracks are decoded into numpy columns (:mod:`gcs.logcolumns`).

Which system is the GCS is read from what only the recorder writes (its team
header, else its ``phase`` values from a system that reports no position);
systems whose HEARTBEAT says ``MAV_TYPE_GCS`` are ground stations too. Neither
becomes a vehicle, and neither counts in the link losses.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gcs.link.dialect import mavlink
from gcs.link.modes import SAFETY_ARMED, heartbeat_mode_text
from gcs.logcolumns import decode_columns
from gcs.logreader import TlogIndex
from gcs.metrics import FlightMetrics
from gcs.phases import Phase
from gcs.recorder import ARRAY_SPAN, ARRAYS, chunked, parse_team_header

__all__ = ["EARTH_RADIUS_M", "FlightLog", "Track"]

_ARRAY_OF = {base + k: name for name, base in ARRAYS.items() for k in range(ARRAY_SPAN)}
_CHUNK_LEN = len(chunked(np.zeros(1000))[0])  # values per DEBUG_FLOAT_ARRAY message
_POSITIONS = ("LOCAL_POSITION_NED", "GLOBAL_POSITION_INT")

EARTH_RADIUS_M = 6_378_137.0
"""Equatorial radius (WGS-84) of the flat-earth conversion of GLOBAL_POSITION_INT, m."""


@dataclass(frozen=True, eq=False)
class Track:
    """One vehicle's telemetry from its autopilot component, as arrays in time order.

    Positions and attitude as the scene draws them; HEARTBEAT and SYS_STATUS
    so the replay shows mode, armed and battery as the live page does.
    """

    t: np.ndarray  # (K,) Unix s
    p_ned: np.ndarray  # (K, 3) m
    v_ned: np.ndarray  # (K, 3) m/s
    att_t: np.ndarray  # (J,) Unix s
    rpy: np.ndarray  # (J, 3) rad
    hb_t: np.ndarray  # (H,) Unix s
    armed: np.ndarray  # (H,) bool
    autopilot: np.ndarray  # (H,) MAV_AUTOPILOT
    custom_mode: np.ndarray  # (H,) autopilot-specific mode number
    battery_t: np.ndarray  # (B,) Unix s
    battery: np.ndarray  # (B,) % remaining, NaN where the autopilot does not know

    def mode(self, k: int) -> str:
        """Flight mode named by heartbeat ``k``."""
        return heartbeat_mode_text(int(self.autopilot[k]), int(self.custom_mode[k]))


@dataclass(eq=False)
class FlightLog:
    """Everything a replay or a report needs from one .tlog."""

    index: TlogIndex
    gcs_sysid: int | None  # the recorder's GCS
    ground: frozenset[int]  # every ground station's system (the GCS's and MAV_TYPE_GCS ones)
    team: dict[str, object] | None
    tick_t: np.ndarray  # (K,) Unix s
    phase: np.ndarray  # (K,) int
    values: dict[str, np.ndarray]  # NAMED_VALUE_FLOAT per tick: stk_fwd, scale, alt_tgt...
    arrays: dict[str, np.ndarray]  # per tick: dist_err (K, m), acc_cmd (K, 2n), tilt...
    tracks: dict[int, Track]
    texts: list[tuple[float, int, int, str]]  # (t, sysid, severity, text)
    missing: list[str] = field(default_factory=list)
    origin: tuple[float, float, float] | None = None  # lat, lon (deg), alt (m) of NED zero

    @classmethod
    def load(cls, path: str | Path,
             progress: Callable[[str, int, int], None] | None = None) -> FlightLog:
        """Read ``path``; LogError if it holds no MAVLink at all."""
        index = TlogIndex.build(path, progress=(lambda d, n: progress("index", d, n))
                                if progress else None)
        gcs_sysid = _gcs_system(index)
        ground = _ground_stations(index) | ({gcs_sysid} if gcs_sysid is not None else set())
        ticks: dict[int, dict[str, object]] = defaultdict(dict)
        team = None
        if gcs_sysid is not None:
            team = _read_internals(index, gcs_sysid, ticks, progress)
        tracks, origin = _read_tracks(index, ground)
        texts = _read_texts(index)
        log = cls(index=index, gcs_sysid=gcs_sysid, ground=frozenset(ground), team=team,
                  tick_t=np.zeros(0), phase=np.zeros(0, dtype=int), values={}, arrays={},
                  tracks=tracks, texts=texts, origin=origin)
        log._assemble(ticks)
        return log

    def link_losses(self) -> dict[tuple[int, int], int]:
        """Frames missing per (system, component) of what the vehicles sent, as received.

        The ground stations' own frames are left out: several senders of the GCS
        share its system id, each with its own sequence counter.
        """
        return self.index.streams_lost(s for s in self.index.systems() if s not in self.ground)

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
            self.missing.append("vehicle positions (no LOCAL_POSITION_NED or "
                                "GLOBAL_POSITION_INT)")
        elif self.origin is not None:
            lat, lon, alt = self.origin
            self.missing.append(f"local positions (drawn from GLOBAL_POSITION_INT about "
                                f"{lat:.6f}, {lon:.6f}, {alt:.1f} m, flat earth)")

    @property
    def n_vehicles(self) -> int:
        if self.team is not None:
            return len(self.team["ids"])  # type: ignore[arg-type]
        return len(self.tracks)

    def metrics(self) -> FlightMetrics:
        """The flight metrics, computed exactly as ``gcs fly`` computes them live.

        A tick whose truth lost a piece (a corrupt log) adds no truth figures.
        """
        m = FlightMetrics()
        n = self.n_vehicles
        de = self.arrays.get("dist_err", np.full((len(self.tick_t), 1), np.nan))
        acc = self.per_vehicle("acc_cmd", 2)
        tilt = self.per_vehicle("tilt", 1)
        truth = all(k in self.arrays for k in ("payload", "rope_T", "veh_true"))
        true_p, rope = self.per_vehicle("veh_true", 3), self.per_vehicle("rope_T", 1)
        for k, t in enumerate(self.tick_t):
            payload = self.arrays["payload"][k, :3] if truth else None
            whole = truth and bool(np.isfinite(payload).all() and np.isfinite(true_p[k]).all()
                                   and np.isfinite(rope[k]).all())
            m.add_tick(
                t - self.tick_t[0], Phase(int(self.phase[k])), distance_errors=de[k],
                tilt=tilt[k, :, 0], accel_cmd=np.nan_to_num(acc[k]) if n else np.zeros((1, 2)),
                vehicles_true=true_p[k] if whole else None, payload=payload if whole else None,
                rope_tension=rope[k, :, 0] if whole else None)
        return m

    def per_vehicle(self, name: str, columns: int) -> np.ndarray:
        """Array ``name`` as (ticks, vehicles, columns), NaN where it was not recorded."""
        n = self.n_vehicles
        out = np.full((len(self.tick_t), n * columns), np.nan)
        a = self.arrays.get(name)
        if a is not None:
            width = min(a.shape[1], n * columns)
            out[:, :width] = a[:, :width]
        return out.reshape(len(self.tick_t), n, columns)

    def phase_changes(self) -> list[tuple[float, str]]:
        """(time, phase name) at each change of phase."""
        out = []
        for k in range(len(self.phase)):
            if k == 0 or self.phase[k] != self.phase[k - 1]:
                out.append((float(self.tick_t[k]), Phase(int(self.phase[k])).text))
        return out


def _gcs_system(index: TlogIndex) -> int | None:
    """The recorder's GCS: who sent the team header, else the ``phase`` values.

    Autopilot scripts send NAMED_VALUE_INT too, so a count of those would pick
    a busy vehicle; ``phase`` values only count from a system that reports no
    position (a vehicle is never the GCS). None for a plain autopilot log.
    """
    header = _team_sender(index)
    if header is not None:
        return header
    vehicles = {int(s) for name in _POSITIONS for s in index.sysid[index.select(name)]}
    recs = index.select("NAMED_VALUE_INT")
    recs = recs[~np.isin(index.sysid[recs], list(vehicles))]
    named = decode_columns(index.path, index.offset, recs, "NAMED_VALUE_INT")["name"]
    senders = index.sysid[recs][named == b"phase"]
    return int(np.bincount(senders).argmax()) if len(senders) else None


def _team_sender(index: TlogIndex, chunk: int = 4096) -> int | None:
    """System of the first team header (written once, at the start, by the recorder)."""
    recs = index.select("DEBUG_FLOAT_ARRAY")
    first = ARRAYS["team"]
    for lo in range(0, len(recs), chunk):
        part = recs[lo : lo + chunk]
        cols = decode_columns(index.path, index.offset, part, "DEBUG_FLOAT_ARRAY")
        hit = np.flatnonzero((cols["name"] == b"team") & (cols["array_id"] >= first) &
                             (cols["array_id"] < first + ARRAY_SPAN))
        if len(hit):
            return int(index.sysid[part[hit[0]]])
    return None


def _ground_stations(index: TlogIndex) -> set[int]:
    """Systems whose HEARTBEAT says they are a ground station (MAV_TYPE_GCS)."""
    recs = index.select("HEARTBEAT")
    kind = decode_columns(index.path, index.offset, recs, "HEARTBEAT")["type"]
    return {int(s) for s in np.unique(index.sysid[recs][kind == mavlink.MAV_TYPE_GCS])}


def _read_internals(index: TlogIndex, gcs: int, ticks: dict[int, dict[str, object]],
                    progress: Callable[[str, int, int], None] | None) -> dict | None:
    """Fill ``ticks`` (recorder time stamp -> values) from the GCS's messages; the team.

    Decoded as numpy columns (:mod:`gcs.logcolumns`): a DEBUG_FLOAT_ARRAY as
    a list of Python floats held about 2 kB until its tick was assembled, so
    an hour of flight took over 250 MB here.
    """
    kinds = ("NAMED_VALUE_FLOAT", "NAMED_VALUE_INT", "DEBUG_FLOAT_ARRAY")
    selected = [index.select(kind, sysid=gcs) for kind in kinds]
    total = sum(len(r) for r in selected)
    done = 0
    parts: dict[tuple[int, str], dict[int, np.ndarray]] = defaultdict(dict)
    for kind, recs in zip(kinds, selected, strict=True):
        cols = decode_columns(index.path, index.offset, recs, kind)
        times = index.t[recs]
        stamps = np.round(times * 1e6).astype(np.int64).tolist()  # a tick's shared stamp
        if kind == "DEBUG_FLOAT_ARRAY":
            data = cols["data"]
            for k, (stamp, array_id) in enumerate(zip(stamps, cols["array_id"].tolist(),
                                                      strict=True)):
                name = _ARRAY_OF.get(array_id)
                if name is not None:
                    parts[(stamp, name)][array_id - ARRAYS[name]] = data[k]
        else:
            for stamp, t, key, value in zip(stamps, times.tolist(), _texts(cols["name"]),
                                            cols["value"].tolist(), strict=True):
                tick = ticks[stamp]
                tick["t"] = t
                tick[key] = value
        done += len(recs)
        if progress is not None:
            progress("decode", done, total)
    team = None
    for (stamp, name), chunks in parts.items():
        flat = _join(chunks)
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


def _read_texts(index: TlogIndex) -> list[tuple[float, int, int, str]]:
    """Every STATUSTEXT as (Unix time, system id, severity, text)."""
    recs = index.select("STATUSTEXT")
    cols = decode_columns(index.path, index.offset, recs, "STATUSTEXT")
    return list(zip(index.t[recs].tolist(), index.sysid[recs].tolist(),
                    cols["severity"].tolist(), _texts(cols["text"]), strict=True))


def _texts(column: np.ndarray) -> list[str]:
    """A char[] column as strings, cut at the first NUL as pymavlink does."""
    return [bytes(v).split(b"\0", 1)[0].decode("utf-8", "replace") for v in column]


def _join(chunks: dict[int, np.ndarray]) -> np.ndarray:
    """One array from its DEBUG_FLOAT_ARRAY chunks, each at its place (NaN for a lost one)."""
    flat = np.full((max(chunks) + 1) * _CHUNK_LEN, np.nan)
    for k, values in chunks.items():
        flat[k * _CHUNK_LEN : k * _CHUNK_LEN + len(values)] = values
    return flat


def _trim(name: str, flat: np.ndarray, team: dict | None) -> np.ndarray:
    """The array at its size when the team is known: the last chunk's zero padding cut,
    a lost last chunk NaN, so every tick's row has the width the team says."""
    if team is None:
        return flat
    n = len(team["ids"])
    m = len(team["distances"])
    size = {"dist_err": m, "acc_cmd": 2 * n, "tilt": n, "payload": 6, "rope_T": n,
            "veh_true": 3 * n}.get(name)
    if size is None:
        return flat
    out = np.full(size, np.nan)
    out[: min(size, len(flat))] = flat[:size]
    return out


def _read_tracks(index: TlogIndex, ground: set[int]
                 ) -> tuple[dict[int, Track], tuple[float, float, float] | None]:
    """Every vehicle's track, and the GLOBAL_POSITION_INT origin if any track needed one.

    A vehicle is a system, not a ground station, whose autopilot component
    (the one that sends its positions) reported at least one position.
    """
    tracks: dict[int, Track] = {}
    origin = None
    for sysid in index.systems():
        if sysid in ground:
            continue
        comp, name = _position_source(index, sysid)
        if comp is None:
            continue
        if name == "LOCAL_POSITION_NED":
            t, p, v = _local_positions(index, sysid, comp)
        else:
            t, lat, lon, alt, v = _global_positions(index, sysid, comp)
            if origin is None and len(t):
                origin = (float(lat[0]), float(lon[0]), float(alt[0]))
            p = _flat_earth(lat, lon, alt, origin) if len(t) else np.zeros((0, 3))
        if len(t):
            tracks[sysid] = _track(index, sysid, comp, t, p, v)
    return tracks, origin


def _position_source(index: TlogIndex, sysid: int) -> tuple[int | None, str]:
    """(component, message) that carries ``sysid``'s positions, local NED preferred."""
    for name in _POSITIONS:
        recs = index.select(name, sysid=sysid)
        if len(recs):
            return int(np.bincount(index.compid[recs]).argmax()), name
    return None, ""


def _columns(index: TlogIndex, name: str, sysid: int, comp: int
             ) -> tuple[np.ndarray, np.ndarray]:
    """Times and decoded fields of one component's ``name`` messages, in time order."""
    recs = index.select(name, sysid=sysid)
    recs = recs[index.compid[recs] == comp]
    recs = recs[np.argsort(index.t[recs], kind="stable")]
    return index.t[recs], decode_columns(index.path, index.offset, recs, name)


def _local_positions(index: TlogIndex, sysid: int, comp: int
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t, c = _columns(index, "LOCAL_POSITION_NED", sysid, comp)
    return (t, np.column_stack((c["x"], c["y"], c["z"])).astype(float),
            np.column_stack((c["vx"], c["vy"], c["vz"])).astype(float))


def _global_positions(index: TlogIndex, sysid: int, comp: int) -> tuple[np.ndarray, ...]:
    """Times, latitude, longitude (deg), altitude (m) and NED velocity of the fixes.

    A fix at exactly 0, 0 is the autopilot saying it has none.
    """
    t, c = _columns(index, "GLOBAL_POSITION_INT", sysid, comp)
    fix = (c["lat"] != 0) | (c["lon"] != 0)
    c = c[fix]
    v = np.column_stack((c["vx"], c["vy"], c["vz"])).astype(float) * 0.01
    return t[fix], c["lat"] * 1e-7, c["lon"] * 1e-7, c["alt"] * 1e-3, v


def _flat_earth(lat: np.ndarray, lon: np.ndarray, alt: np.ndarray,
                origin: tuple[float, float, float]) -> np.ndarray:
    """North, east, down about ``origin`` on a flat earth (a sphere's tangent plane).

    Good to centimetres over the few hundred metres a team flies; heights are
    the autopilot's altitude above mean sea level, relative to the origin's.
    """
    lat0, lon0, alt0 = origin
    north = np.radians(lat - lat0) * EARTH_RADIUS_M
    east = np.radians(lon - lon0) * EARTH_RADIUS_M * np.cos(np.radians(lat0))
    return np.column_stack((north, east, -(alt - alt0)))


def _track(index: TlogIndex, sysid: int, comp: int, t: np.ndarray, p: np.ndarray,
           v: np.ndarray) -> Track:
    """Positions with the same component's attitude, heartbeats and battery."""
    att_t, att = _columns(index, "ATTITUDE", sysid, comp)
    hb_t, hb = _columns(index, "HEARTBEAT", sysid, comp)
    bat_t, bat = _columns(index, "SYS_STATUS", sysid, comp)
    remaining = bat["battery_remaining"].astype(float)
    return Track(t=t, p_ned=p, v_ned=v, att_t=att_t,
                 rpy=np.column_stack((att["roll"], att["pitch"], att["yaw"])).astype(float),
                 hb_t=hb_t, armed=(hb["base_mode"] & SAFETY_ARMED) != 0,
                 autopilot=hb["autopilot"], custom_mode=hb["custom_mode"], battery_t=bat_t,
                 battery=np.where(remaining >= 0, remaining, np.nan))
