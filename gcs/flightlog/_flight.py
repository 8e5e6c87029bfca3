"""A recorded flight read back as arrays: guidance ticks, vehicle tracks, events.

Works on logs written by the GCS's recorder (with guidance internals, team
header and, in simulation, ground truth) and on plain telemetry logs of real
autopilots (then only the vehicle tracks and texts exist; ``missing`` says what
is absent). Only the message types used are decoded, through the index; the
vehicle tracks are decoded into numpy columns (:mod:`gcs.flightlog._columns`).

Which system is the GCS is read from what only the recorder writes (its team
header, else its ``phase`` values from a system that reports no position);
systems whose HEARTBEAT says ``MAV_TYPE_GCS`` are ground stations too. Neither
becomes a vehicle, and neither counts in the link losses. Every other system
with an autopilot component is a vehicle, whether or not its positions were
logged (see :func:`_team_frame` for where each one is placed).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gcs.flightlog._columns import decode_columns
from gcs.flightlog._metrics import FlightMetrics
from gcs.flightlog._reader import TlogIndex
from gcs.flightlog._recorder import ARRAY_SPAN, ARRAYS, TeamHeader, chunked, parse_team_header
from gcs.loop import Phase
from gcs.wire import (
    SAFETY_ARMED,
    geodetic_median,
    geodetic_to_ned,
    heartbeat_mode_text,
    local_origin,
    mavlink,
    message_id,
)

__all__ = ["ORIGIN_TOLERANCE_M", "FlightLog", "Track", "tilt_angle"]

_ARRAY_OF = {base + k: name for name, base in ARRAYS.items() for k in range(ARRAY_SPAN)}
_CHUNK_LEN = len(chunked(np.zeros(1000))[0])  # values per DEBUG_FLOAT_ARRAY message
_POSITIONS = ("LOCAL_POSITION_NED", "GLOBAL_POSITION_INT")
_TRACK_MESSAGES = (*_POSITIONS, "ATTITUDE", "HEARTBEAT", "SYS_STATUS")
_MATCH_S = 0.5  # a local and a global position this close in time describe one moment

ORIGIN_TOLERANCE_M = 1.0
"""Vehicles' LOCAL_POSITION_NED origins further apart than this are different frames, m."""


def tilt_angle(rpy: np.ndarray) -> np.ndarray:
    """Angle between body and world vertical from roll and pitch (``rpy[..., :2]``), rad."""
    return np.arccos(np.clip(np.cos(rpy[..., 0]) * np.cos(rpy[..., 1]), -1.0, 1.0))


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
    team: TeamHeader | None
    tick_t: np.ndarray  # (K,) Unix s
    phase: np.ndarray  # (K,) int
    values: dict[str, np.ndarray]  # NAMED_VALUE_FLOAT per tick: stk_fwd, scale, alt_tgt...
    arrays: dict[str, np.ndarray]  # per tick: dist_err (K, m), acc_cmd (K, 2n), tilt...
    tracks: dict[int, Track]
    texts: list[tuple[float, int, int, str]]  # (t, sysid, severity, text)
    missing: list[str] = field(default_factory=list)
    origin: tuple[float, float, float] | None = None  # lat, lon (deg), alt (m) of NED zero
    origin_spread: float = 0.0  # m, how far apart the vehicles' local origins are
    local_origins: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    """Each vehicle's LOCAL_POSITION_NED origin (lat, lon, alt) where GLOBAL_POSITION_INT
    beside it shows it (:func:`gcs.wire.local_origin`, as the live team frame takes it)."""
    from_global: tuple[int, ...] = ()  # vehicles placed from GLOBAL_POSITION_INT
    own_frame: tuple[int, ...] = ()  # vehicles with local positions only, left unplaced

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
        tracks, frame = _read_tracks(index, ground, progress)
        texts = _read_texts(index)
        log = cls(index=index, gcs_sysid=gcs_sysid, ground=frozenset(ground), team=team,
                  tick_t=np.zeros(0), phase=np.zeros(0, dtype=int), values={}, arrays={},
                  tracks=tracks, texts=texts, origin=frame.origin, origin_spread=frame.spread,
                  local_origins=frame.local_origins, from_global=frame.from_global,
                  own_frame=frame.own_frame)
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
            self.missing.append("guidance internals (no GCS messages: a plain autopilot log), "
                                "so no phases, per-phase distance errors, payload swing or "
                                "commanded accelerations")
        if self.team is None:
            self.missing.append("team header (edges and desired distances)")
        if "payload" not in self.arrays:
            self.missing.append("payload and rope truth (only recorded in simulation)")
        unplaced = [s for s, tr in sorted(self.tracks.items())
                    if not len(tr.t) and s not in self.own_frame]
        if not self.tracks or unplaced:
            self.missing.append(f"vehicle positions{_whose(unplaced)} (no LOCAL_POSITION_NED "
                                "or GLOBAL_POSITION_INT)")
        if self.origin is not None:
            lat, lon, alt = self.origin
            if self.origin_spread > ORIGIN_TOLERANCE_M:
                why = ("a shared local frame (the vehicles' LOCAL_POSITION_NED origins differ "
                       f"by up to {self.origin_spread:.1f} m)")
            elif self.own_frame:
                why = ("a shared local frame (no vehicle sent both LOCAL_POSITION_NED and "
                       "GLOBAL_POSITION_INT, to tie the two)")
            elif {s for s, tr in self.tracks.items() if len(tr.t)} <= set(self.from_global):
                why = "local positions"
            else:
                why = f"local positions{_whose(self.from_global)} (about the others' local origin)"
            self.missing.append(f"{why}: drawn from GLOBAL_POSITION_INT about "
                                f"{lat:.6f}, {lon:.6f}, {alt:.1f} m, WGS-84")
        if self.own_frame:
            self.missing.append(f"vehicle positions{_whose(self.own_frame)} in the team's frame "
                                "(only LOCAL_POSITION_NED, about an origin no GLOBAL_POSITION_INT "
                                "ties to the others'): not placed")

    @property
    def n_vehicles(self) -> int:
        if self.team is not None:
            return len(self.team["ids"])
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
            whole = payload is not None and bool(
                np.isfinite(payload).all() and np.isfinite(true_p[k]).all()
                and np.isfinite(rope[k]).all())
            m.add_tick(
                t - self.tick_t[0], Phase(int(self.phase[k])), distance_errors=de[k],
                tilt=tilt[k, :, 0], accel_cmd=np.nan_to_num(acc[k]) if n else np.zeros((1, 2)),
                vehicles_true=true_p[k] if whole else None, payload=payload if whole else None,
                rope_tension=rope[k, :, 0] if whole else None)
        return m

    def telemetry_metrics(self) -> dict[str, object]:
        """What the vehicles' telemetry alone gives, for a log without guidance ticks.

        A plain autopilot log has no ticks, so :meth:`metrics` has nothing to
        count; its telemetry still tells how long the vehicles were logged and
        how far they banked while armed (each ATTITUDE against the latest
        HEARTBEAT before it). The keys are those of :meth:`metrics`; what needs
        the guidance internals is None.
        """
        spans = [a for tr in self.tracks.values()
                 for a in (tr.t, tr.att_t, tr.hb_t, tr.battery_t) if len(a)]
        m = FlightMetrics()
        if spans:
            m.start = min(float(a[0]) for a in spans)
            m.end = max(float(a[-1]) for a in spans)
        banks = []
        for tr in self.tracks.values():
            if len(tr.hb_t):
                hb = np.searchsorted(tr.hb_t, tr.att_t, side="right") - 1
                banks.append(tilt_angle(tr.rpy[(hb >= 0) & tr.armed[np.maximum(hb, 0)]]))
        bank = np.concatenate(banks) if banks else np.zeros(0)
        out = m.to_json()
        out.update(worst_distance_error_m=None, worst_accel_cmd_m_s2=None,
                   worst_bank_rad=round(float(bank.max()), 4) if len(bank) else None)
        return out

    def per_vehicle(self, name: str, columns: int) -> np.ndarray:
        """Array ``name`` as (ticks, vehicles, columns), NaN where it was not recorded."""
        n = self.n_vehicles
        out = np.full((len(self.tick_t), n * columns), np.nan)
        a = self.arrays.get(name)
        if a is not None:
            width = min(a.shape[1], n * columns)
            out[:, :width] = a[:, :width]
        return out.reshape(len(self.tick_t), n, columns)

    def cut_short(self) -> str | None:
        """Why the flight's record ends with the team possibly in the air (the GCS was
        stopped or killed, the log cut), or None when it ends on the ground.

        A complete flight ends landed, or never took off; a log of the GCS whose last
        phase is an airborne one did not see the team come down.
        """
        if not len(self.phase):
            return None
        last = Phase(int(self.phase[-1]))
        if not last.airborne:
            return None
        return (f"cut short: the record ends in phase {last.text} at "
                f"t = {float(self.tick_t[-1] - self.tick_t[0]):.1f} s, with no landing")

    def phase_changes(self) -> list[tuple[float, str]]:
        """(time, phase name) at each change of phase."""
        out = []
        for k in range(len(self.phase)):
            if k == 0 or self.phase[k] != self.phase[k - 1]:
                out.append((float(self.tick_t[k]), Phase(int(self.phase[k])).text))
        return out


def _whose(vehicles: list[int] | tuple[int, ...]) -> str:
    """`` from vehicle 1, 3`` for a ``missing`` line, or nothing for none."""
    return f" from vehicle {', '.join(map(str, vehicles))}" if vehicles else ""


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
                    progress: Callable[[str, int, int], None] | None) -> TeamHeader | None:
    """Fill ``ticks`` (recorder time stamp -> values) from the GCS's messages; the team.

    Decoded as numpy columns (:mod:`gcs.flightlog._columns`): a DEBUG_FLOAT_ARRAY as
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


def _trim(name: str, flat: np.ndarray, team: TeamHeader | None) -> np.ndarray:
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


_Samples = tuple[np.ndarray, np.ndarray, np.ndarray]
"""Times (K,), positions (K, 3) and velocities (K, 3) of one vehicle, in time order: local
positions in NED (m), or fixes as latitude, longitude (deg) and altitude (m)."""

_Lla = tuple[float, float, float]


@dataclass(frozen=True)
class _Frame:
    """The team's one frame: each placed vehicle's samples in it, and how it was found."""

    positions: dict[int, _Samples]
    from_global: tuple[int, ...]  # placed from GLOBAL_POSITION_INT
    origin: _Lla | None  # NED zero (lat, lon, alt) when any was
    spread: float  # m, how far apart the measured LOCAL_POSITION_NED origins are
    own_frame: tuple[int, ...]  # only local positions, about an origin not known: unplaced
    local_origins: dict[int, _Lla]  # each measured LOCAL_POSITION_NED origin


def _read_tracks(index: TlogIndex, ground: set[int],
                 progress: Callable[[str, int, int], None] | None = None
                 ) -> tuple[dict[int, Track], _Frame]:
    """Every vehicle's track, placed in the team's one frame (:func:`_team_frame`).

    A vehicle is a system, not a ground station, with an autopilot component:
    the one that sends its positions, else the one whose HEARTBEAT names an
    autopilot. A vehicle whose positions were not logged, or not placed, is
    kept (its mode, attitude and battery are still worth seeing), its position
    unknown.
    """
    vehicles = {s: c for s in index.systems() if s not in ground
                and (c := _autopilot_component(index, s)) is not None}
    local: dict[int, _Samples] = {}
    fixes: dict[int, _Samples] = {}
    for sysid, comp in vehicles.items():
        if len((track := _local_positions(index, sysid, comp))[0]):
            local[sysid] = track
        if len((fix := _global_positions(index, sysid, comp))[0]):
            fixes[sysid] = fix
    frame = _team_frame(local, fixes)
    wanted = np.isin(index.msgid, [message_id(name) for name in _TRACK_MESSAGES])
    counts = np.bincount(index.sysid[wanted], minlength=256)
    total, done = int(sum(counts[s] for s in vehicles)), 0
    nowhere = (np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)))
    tracks: dict[int, Track] = {}
    for sysid, comp in vehicles.items():
        tracks[sysid] = _track(index, sysid, comp, *frame.positions.get(sysid, nowhere))
        done += int(counts[sysid])
        if progress is not None:
            progress("tracks", done, total)
    return tracks, frame


def _team_frame(local: dict[int, _Samples], fixes: dict[int, _Samples]) -> _Frame:
    """Where each vehicle is placed: one rule, so the distances between them mean something.

    Each autopilot sets its LOCAL_POSITION_NED origin where its estimator
    started, unless the GCS set one for all; a vehicle that sends
    GLOBAL_POSITION_INT too shows its origin (:func:`_local_origins`).

    - The local frame, when it can hold every vehicle: the measured origins agree
      within :data:`ORIGIN_TOLERANCE_M` and, if a vehicle sends only fixes, at
      least one origin was measured. Vehicles with local positions are placed
      from them (one that sends only those is taken to share the origin); one
      with only fixes in NED about the shared origin (their median), z included.
    - Else the GPS frame: every vehicle with fixes is placed from them, NED about
      the first fix of the lowest system id; one that sends only local positions
      is not placed, its origin being unknown.

    NED is the WGS-84 tangent plane of :mod:`gcs.wire`, as in the live team frame.
    """
    reference = fixes[min(fixes)][1][0] if fixes else None
    origins = _local_origins(local, fixes)
    o = (geodetic_to_ned(np.array(list(origins.values())), reference)
         if origins and reference is not None else np.zeros((0, 3)))
    spread = float(np.linalg.norm(o[:, None] - o[None, :], axis=2).max()) if len(o) else 0.0
    gps_only = sorted(set(fixes) - set(local))
    measured = {s: _lla(lla) for s, lla in origins.items()}
    if spread <= ORIGIN_TOLERANCE_M and (origins or not gps_only):
        positions = dict(local)
        origin = None
        if gps_only:
            zero = geodetic_median(list(origins.values()))
            for s in gps_only:
                t, lla, v = fixes[s]
                positions[s] = (t, geodetic_to_ned(lla, zero), v)
            origin = _lla(zero)
        return _Frame(positions, tuple(gps_only), origin, spread, (), measured)
    assert reference is not None  # the GPS frame only when some vehicle sent fixes
    positions = {s: (t, geodetic_to_ned(lla, reference), v) for s, (t, lla, v) in fixes.items()}
    return _Frame(positions, tuple(sorted(fixes)), _lla(reference), spread,
                  tuple(sorted(set(local) - set(fixes))), measured)


def _lla(a: np.ndarray) -> _Lla:
    return float(a[0]), float(a[1]), float(a[2])


def _autopilot_component(index: TlogIndex, sysid: int) -> int | None:
    """The component of ``sysid`` that sends its positions, else the one whose HEARTBEAT
    names an autopilot (a gimbal's or a companion computer's names none); None if neither."""
    recs = np.concatenate([index.select(name, sysid=sysid) for name in _POSITIONS])
    if not len(recs):
        recs = index.select("HEARTBEAT", sysid=sysid)
        kind = decode_columns(index.path, index.offset, recs, "HEARTBEAT")["autopilot"]
        recs = recs[kind != mavlink.MAV_AUTOPILOT_INVALID]
    return int(np.bincount(index.compid[recs]).argmax()) if len(recs) else None


def _local_origins(local: dict[int, _Samples], fixes: dict[int, _Samples]
                   ) -> dict[int, np.ndarray]:
    """Each vehicle's LOCAL_POSITION_NED origin (lat, lon, alt), where known.

    Its fixes each beside its local position at the same moment (the latest
    local sample at most :data:`_MATCH_S` before the fix), through
    :func:`gcs.wire.local_origin`. Only vehicles that send both, at matching times.
    """
    origins = {}
    for sysid, (tl, pl, _) in local.items():
        if sysid not in fixes:
            continue
        tg, lla, _ = fixes[sysid]
        k = np.searchsorted(tl, tg, side="right") - 1
        near = (k >= 0) & (tg - tl[np.maximum(k, 0)] <= _MATCH_S)
        if near.any():
            origins[sysid] = local_origin(lla[near], pl[k[near]])
    return origins


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


def _global_positions(index: TlogIndex, sysid: int, comp: int) -> _Samples:
    """Times, latitude, longitude (deg) and altitude (m), and NED velocity of the fixes.

    A fix at exactly 0, 0 is the autopilot saying it has none.
    """
    t, c = _columns(index, "GLOBAL_POSITION_INT", sysid, comp)
    fix = (c["lat"] != 0) | (c["lon"] != 0)
    c = c[fix]
    v = np.column_stack((c["vx"], c["vy"], c["vz"])).astype(float) * 0.01
    return t[fix], np.column_stack((c["lat"] * 1e-7, c["lon"] * 1e-7, c["alt"] * 1e-3)), v


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
