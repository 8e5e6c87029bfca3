"""A recorded flight as the state at any moment: what the replay page draws.

:class:`ReplayCursor` turns a :class:`~gcs.flightlog.FlightLog` into the same
arrays the live page draws from (a :class:`~gcs.loop.FleetState` and, in
simulation, a :class:`~gcs.wire.SimTruth`), so the replay reuses the live
scene code unchanged. It is stateless: the state at ``t`` depends on ``t`` only,
so scrubbing backwards is as exact as playing forwards.

Vehicle states are the latest recorded sample at or before ``t`` (not
interpolated: what is drawn is what was received), mode, armed and battery
included, so the live page's vehicle states (ok, stale, holding, landing) come
out of the same code; guidance internals are those of the latest tick at or
before ``t``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs.flightlog import FlightLog, Track, tilt_angle
from gcs.loop import FleetState, Phase
from gcs.wire import SimTruth, vec3
from web._frame import TeamView

__all__ = ["ReplayCursor", "ReplayEvent", "ReplayState", "replay_view"]

DEFAULT_ROPE_LENGTH = 1.0
"""Rope length assumed when drawing a payload the log does not hold, m."""

_WARNING = 4  # MAV_SEVERITY_WARNING: this and more severe (lower) are warnings
_ERROR = 3  # MAV_SEVERITY_ERROR: this and more severe are errors
_PHASE_TEXTS = frozenset(f"phase: {p.text}" for p in Phase)  # what the runtime writes


@dataclass(frozen=True)
class ReplayEvent:
    """One moment worth jumping to: a phase change or a STATUSTEXT."""

    t: float  # Unix s
    kind: str  # "phase", "warning" or "text"
    text: str  # the GCS's own as it wrote them; a vehicle's prefixed "<sysid>: "
    level: str = "info"  # "info", "warning" or "error", as the live page's events


@dataclass(frozen=True, eq=False)
class ReplayState:
    """The recorded state at time ``t``."""

    t: float
    fleet: FleetState
    tick: int  # index of the latest guidance tick <= t, -1 before the first (or none)
    phase: Phase | None
    values: dict[str, float]  # that tick's named values (stk_fwd, scale, alt_tgt...)
    arrays: dict[str, np.ndarray]  # that tick's arrays (dist_err, acc_cmd, tilt...)
    truth: SimTruth | None  # payload and rope tensions, simulation logs only
    events: list[ReplayEvent]  # every event at or before t, oldest first

    @property
    def scale(self) -> float:
        s = self.values.get("scale", math.nan)
        return s if math.isfinite(s) else 1.0


def _latest(times: np.ndarray, t: float) -> int:
    """Index of the latest time <= t, -1 if none."""
    return int(np.searchsorted(times, t, side="right")) - 1


class ReplayCursor:
    """Random access to a flight log by time.

    Args:
        log: the loaded flight.
    """

    def __init__(self, log: FlightLog) -> None:
        self.log = log
        team = log.team
        self.ids: tuple[int, ...] = (tuple(team["ids"]) if team is not None
                                     else tuple(sorted(log.tracks)))
        # the whole log, whatever its records hold: a vehicle without positions
        # (or a log of texts and modes only) still has a timeline to scrub
        self.start = float(log.index.t.min())
        self.end = float(log.index.t.max())
        self.events = _events(log)
        self._event_t = np.array([e.t for e in self.events])

    @property
    def n(self) -> int:
        return len(self.ids)

    def fleet(self, t: float) -> FleetState:
        """Every vehicle's latest recorded telemetry at ``t`` (NaN where none yet)."""
        n = self.n
        p = np.full((n, 3), np.nan)
        v = np.full((n, 3), np.nan)
        yaw = np.zeros(n)
        tilt = np.full(n, np.nan)
        age = np.full(n, np.inf)
        hb_age = np.full(n, np.inf)
        armed = np.zeros(n, dtype=bool)
        battery = np.full(n, np.nan)
        modes = ["unknown"] * n  # as the live table before a vehicle's first HEARTBEAT
        for i, vid in enumerate(self.ids):
            track = self.log.tracks.get(vid)
            if track is None:
                continue
            k = _latest(track.t, t)
            if k >= 0:
                p[i], v[i] = track.p_ned[k], track.v_ned[k]
                age[i] = t - track.t[k]
            j = _latest(track.att_t, t)
            if j >= 0:
                yaw[i] = track.rpy[j, 2]
                tilt[i] = tilt_angle(track.rpy[j])
            hb_age[i], armed[i], modes[i] = _heartbeat(track, t)
            b = _latest(track.battery_t, t)
            if b >= 0:
                battery[i] = track.battery[b]
        return FleetState(t=t, ids=self.ids, p_ned=p, v_ned=v, yaw=yaw, tilt=tilt, age=age,
                          heartbeat_age=hb_age, armed=armed, battery=battery,
                          modes=tuple(modes))

    def tick(self, t: float) -> int:
        """Index of the latest guidance tick at or before ``t`` (-1: none)."""
        return _latest(self.log.tick_t, t)

    def state(self, t: float) -> ReplayState:
        """The recorded state at log time ``t`` (Unix s)."""
        log = self.log
        k = self.tick(t)
        values: dict[str, float] = {}
        arrays: dict[str, np.ndarray] = {}
        phase = None
        truth = None
        if k >= 0:
            phase = Phase(int(log.phase[k]))
            values = {name: float(col[k]) for name, col in log.values.items()}
            arrays = {name: a[k] for name, a in log.arrays.items()}
            truth = self._truth(float(log.tick_t[k]), arrays)
        return ReplayState(t=t, fleet=self.fleet(t), tick=k, phase=phase, values=values,
                           arrays=arrays, truth=truth,
                           events=self.events[: _latest(self._event_t, t) + 1])

    def _truth(self, t: float, arrays: dict[str, np.ndarray]) -> SimTruth | None:
        payload, rope = arrays.get("payload"), arrays.get("rope_T")
        if payload is None or rope is None or not np.isfinite(payload[:6]).all():
            return None
        n = self.n
        true_p = arrays.get("veh_true")
        p = true_p[: 3 * n].reshape(n, 3) if true_p is not None else np.full((n, 3), np.nan)
        return SimTruth(t=t, ids=self.ids,
                        vehicle_p_ned=tuple(vec3(r) for r in p),
                        payload_p_ned=vec3(payload[:3]), payload_v_ned=vec3(payload[3:6]),
                        rope_tension=tuple(float(x) for x in rope[:n]))


def _heartbeat(track: Track, t: float) -> tuple[float, bool, str]:
    """(age, armed, mode) of the latest HEARTBEAT at or before ``t``."""
    k = _latest(track.hb_t, t)
    if k < 0:
        return math.inf, False, "unknown"
    return t - float(track.hb_t[k]), bool(track.armed[k]), track.mode(k)


def _events(log: FlightLog) -> list[ReplayEvent]:
    """Phase changes (from the ticks) and texts, oldest first, each phase change once.

    The GCS also writes each phase change as a text; where the ticks are
    recorded, those texts are left out (the tick's moment is the one whose
    state the page then shows). The GCS's own texts read as the live page
    showed them; a vehicle's are prefixed with its system id.
    """
    events = [ReplayEvent(t, "phase", f"phase: {name}") for t, name in log.phase_changes()]
    ticks = len(log.tick_t) > 0
    events += [ReplayEvent(t, "warning" if sev <= _WARNING else "text",
                           text if sysid == log.gcs_sysid else f"{sysid}: {text}",
                           "error" if sev <= _ERROR else "warning" if sev <= _WARNING
                           else "info")
               for t, sysid, sev, text in log.texts
               if not (ticks and sysid == log.gcs_sysid and text in _PHASE_TEXTS)]
    return sorted(events, key=lambda e: e.t)


def _desired_shape(cursor: ReplayCursor, edges: np.ndarray, distances: np.ndarray) -> np.ndarray:
    """Desired positions (n, 2) from the recorded edge lengths (the header has no positions).

    Least squares on the edge lengths, started from the team's first known
    positions, so the ghost has the recorded distances whatever the start.
    """
    n = cursor.n
    start = np.zeros((n, 2))
    for t in cursor.log.tick_t[:50]:
        p = cursor.fleet(float(t)).p_ned[:, :2]
        if np.isfinite(p).all():
            start = p - p.mean(axis=0)
            break
    if not len(edges) or not np.isfinite(start).all() or not start.any():
        start = np.column_stack((np.cos(2 * np.pi * np.arange(n) / n),
                                 np.sin(2 * np.pi * np.arange(n) / n)))
    from scipy.optimize import least_squares  # only the replay needs it

    def residual(x: np.ndarray) -> np.ndarray:
        q = x.reshape(n, 2)
        return np.linalg.norm(q[edges[:, 0]] - q[edges[:, 1]], axis=1) - distances

    if not len(edges):
        return start
    fit = least_squares(residual, start.ravel())
    q = fit.x.reshape(n, 2)
    return q - q.mean(axis=0)


def replay_view(cursor: ReplayCursor, *, stale_after: float = 1.0) -> TeamView:
    """The :class:`TeamView` of a recorded team, from its header (or none, for plain logs).

    Rope length and the nominal tension are not recorded: the tension colour scale
    is centred on the flight's median tension, the rope length is a default.
    """
    team = cursor.log.team
    n = cursor.n
    if team is None:
        edges = np.zeros((0, 2), dtype=int)
        distances = np.zeros(0)
    else:
        edges = np.asarray(team["edges"], dtype=int).reshape(-1, 2)
        distances = np.asarray(team["distances"], dtype=float)
    rope = cursor.log.arrays.get("rope_T")
    taut = rope[np.isfinite(rope) & (rope > 0.05)] if rope is not None else np.zeros(0)
    nominal = float(np.median(taut)) if len(taut) else 1.0
    return TeamView(ids=cursor.ids, desired_xy=_desired_shape(cursor, edges, distances)
                    if n else np.zeros((0, 2)), edges=edges, distances=distances,
                    rope_length=DEFAULT_ROPE_LENGTH, nominal_tension=nominal,
                    stale_after=stale_after)
