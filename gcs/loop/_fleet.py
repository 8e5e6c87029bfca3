"""The team's latest state as arrays, read from the links once per tick.

The loop, the safety rules, the UI and the flight metrics all look at the same
:class:`FleetState`, read in one place: a :class:`FleetTable` the links write
their telemetry into as it arrives.
Unknown values are NaN (never heard) rather than missing entries, so array
code never branches on a vehicle that has not reported yet.
"""

from __future__ import annotations

import functools
import math
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from gcs.common import kernel
from gcs.link import AutopilotProfile
from gcs.wire import (
    Attitude,
    Heartbeat,
    LocalPosition,
    SystemStatus,
    TelemetryRecord,
    ThrustTarget,
)

__all__ = ["FleetState", "FleetTable"]


@dataclass(frozen=True, eq=False)
class FleetState:
    """Latest state of every configured vehicle, in formation order (NED, SI)."""

    t: float
    ids: tuple[int, ...]
    p_ned: np.ndarray  # (n, 3) m
    v_ned: np.ndarray  # (n, 3) m/s
    yaw: np.ndarray  # (n,) rad
    tilt: np.ndarray  # (n,) rad, angle of the thrust axis from the vertical
    age: np.ndarray  # (n,) s since the latest position (inf: never)
    heartbeat_age: np.ndarray  # (n,) s (inf: never)
    armed: np.ndarray  # (n,) bool
    battery: np.ndarray  # (n,) % remaining (NaN: unknown)
    modes: tuple[str, ...]
    thrust: np.ndarray | None = None
    """(n,) collective thrust, 0 .. 1 of each autopilot's own scale (below 0: reverse or
    spooling down; NaN: none heard);
    None where no thrust is read (a replay)."""
    thrust_age: np.ndarray | None = None
    """(n,) s since the latest thrust (inf: never)."""

    @property
    def n(self) -> int:
        return len(self.ids)

    @functools.cached_property
    def located(self) -> bool:
        """Whether every vehicle's horizontal position and velocity are known (finite)."""
        return _all_finite(self.p_ned, self.v_ned)


_P, _V, _T_POS = slice(0, 3), slice(3, 6), 6  # columns of the table
_ROLL, _PITCH, _YAW, _T_ATT = 7, 8, 9, 10
_T_HB, _ARMED, _BATTERY = 11, 12, 13
_THRUST, _T_THRUST = 14, 15
_COLUMNS = 16


class FleetTable:
    """Every vehicle's latest telemetry in one array, kept current by the links.

    Why: the loop reads the whole team each tick, the UI 25 times a second.
    Taking a snapshot of each link costs a Python call per vehicle (figures:
    docs/performance.md); here each new record is written into its vehicle's
    row as it arrives (on the receive thread), and a read is one copy of the
    array for any team size.

    Args:
        ids: system ids in formation order.
        profiles: each vehicle's autopilot profile (its link and mode names).
    """

    def __init__(self, ids: Sequence[int], profiles: Mapping[int, AutopilotProfile]) -> None:
        self.ids = tuple(ids)
        n = len(self.ids)
        self._rows = np.full((n, _COLUMNS), math.nan)
        self._rows[:, [_T_POS, _T_ATT, _T_HB, _T_THRUST]] = -math.inf
        self._rows[:, _ARMED] = 0.0
        self._modes = ["unknown"] * n
        self._offsets = np.zeros((n, 2))  # each local frame's place in the team frame, m
        self._lock = threading.Lock()
        for i, vid in enumerate(self.ids):
            profile = profiles[vid]
            profile.link.add_record_listener(functools.partial(self._write, i, profile))
            tel = profile.link.telemetry  # what arrived before the listener was there
            for record in (tel.heartbeat, tel.position, tel.attitude, tel.status, tel.thrust):
                if record is not None:
                    self._write(i, profile, record)

    def _write(self, i: int, profile: AutopilotProfile, record: TelemetryRecord) -> None:
        """One record into row ``i``; an older record than the row holds is ignored."""
        rows = self._rows
        if isinstance(record, LocalPosition):
            with self._lock:
                if record.received_at >= rows[i, _T_POS]:
                    rows[i, :7] = (*record.p_ned, *record.v_ned, record.received_at)
        elif isinstance(record, Attitude):
            with self._lock:
                if record.received_at >= rows[i, _T_ATT]:
                    rows[i, 7:11] = (*record.rpy, record.received_at)
        elif isinstance(record, Heartbeat):
            mode = profile.mode_text(record)
            with self._lock:
                if record.received_at >= rows[i, _T_HB]:
                    rows[i, 11:13] = (record.received_at, record.armed)
                    self._modes[i] = mode
        elif isinstance(record, ThrustTarget):
            with self._lock:
                if record.received_at >= rows[i, _T_THRUST]:
                    rows[i, _THRUST:_T_THRUST + 1] = (record.thrust, record.received_at)
        elif isinstance(record, SystemStatus):
            remaining = record.battery_remaining_pct
            with self._lock:
                rows[i, _BATTERY] = math.nan if remaining is None else remaining

    def shift(self, i: int, north: float, east: float) -> None:
        """Place vehicle ``i``'s local frame in the team frame: its origin is ``north``,
        ``east`` (m) from the team's; NaN: unknown, and so is the vehicle's position.

        Why: each real autopilot has its own local origin (:mod:`gcs.loop._team_frame`);
        the offset is added at every read, so a new one applies to the latest position.
        """
        with self._lock:
            self._offsets[i] = (north, east)

    def read(self, now: float) -> FleetState:
        """The team at time ``now`` (the clock that stamps the links' telemetry), its
        positions in the team frame."""
        with self._lock:
            rows = self._rows.copy()
            rows[:, 0:2] += self._offsets
            modes = tuple(self._modes)
        yaw, tilt, age, heartbeat_age, armed = _derived(rows, now)
        return FleetState(t=now, ids=self.ids, p_ned=rows[:, _P], v_ned=rows[:, _V], yaw=yaw,
                          tilt=tilt, age=age, heartbeat_age=heartbeat_age, armed=armed,
                          battery=rows[:, _BATTERY], modes=modes, thrust=rows[:, _THRUST],
                          thrust_age=np.maximum(now - rows[:, _T_THRUST], 0.0))


@kernel()
def _all_finite(p_ned: np.ndarray, v_ned: np.ndarray) -> bool:
    """Whether x and y of every row of both arrays are finite (one compiled pass)."""
    for i in range(p_ned.shape[0]):
        for k in range(2):
            if not (math.isfinite(p_ned[i, k]) and math.isfinite(v_ned[i, k])):
                return False
    return True


@kernel()
def _derived(rows: np.ndarray, now: float) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                    np.ndarray, np.ndarray]:
    """Yaw (0 before any attitude), tilt, ages (>= 0; inf: never heard) and armed flags of
    the table's rows, in one compiled pass (as numpy calls, a sizeable part of the 4 Hz
    tick: docs/performance.md)."""
    n = rows.shape[0]
    yaw, tilt = np.empty(n), np.empty(n)
    age, heartbeat_age = np.empty(n), np.empty(n)
    armed = np.empty(n, np.bool_)
    for i in range(n):
        yaw[i] = rows[i, _YAW] if math.isfinite(rows[i, _T_ATT]) else 0.0
        c = math.cos(rows[i, _ROLL]) * math.cos(rows[i, _PITCH])
        tilt[i] = math.acos(min(1.0, max(-1.0, c))) if math.isfinite(c) else math.nan
        age[i] = max(now - rows[i, _T_POS], 0.0)
        heartbeat_age[i] = max(now - rows[i, _T_HB], 0.0)
        armed[i] = rows[i, _ARMED] > 0.5
    return yaw, tilt, age, heartbeat_age, armed
