"""The team's latest state as arrays, read from the links once per tick.

The loop, the safety rules, the UI and the flight metrics all look at the same
:class:`FleetState`, built in one place from each link's telemetry snapshot.
Unknown values are NaN (never heard) rather than missing entries, so array
code never branches on a vehicle that has not reported yet.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from gcs.link.profile import AutopilotProfile

__all__ = ["FleetState", "read_fleet"]


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

    @property
    def n(self) -> int:
        return len(self.ids)


def read_fleet(ids: Sequence[int], profiles: Mapping[int, AutopilotProfile],
               now: float) -> FleetState:
    """Snapshot every vehicle's telemetry at loop time ``now``."""
    n = len(ids)
    p = np.full((n, 3), np.nan)
    v = np.full((n, 3), np.nan)
    yaw = np.zeros(n)
    tilt = np.full(n, np.nan)
    age = np.full(n, np.inf)
    hb_age = np.full(n, np.inf)
    armed = np.zeros(n, dtype=bool)
    battery = np.full(n, np.nan)
    modes: list[str] = []
    for i, vid in enumerate(ids):
        profile = profiles[vid]
        tel = profile.link.telemetry
        if tel.position is not None:
            p[i] = tel.position.p_ned
            v[i] = tel.position.v_ned
            age[i] = max(0.0, now - tel.position.received_at)
        if tel.attitude is not None:
            roll, pitch, yaw[i] = tel.attitude.rpy
            tilt[i] = math.acos(max(-1.0, min(1.0, math.cos(roll) * math.cos(pitch))))
        if tel.heartbeat is not None:
            hb_age[i] = max(0.0, now - tel.heartbeat.received_at)
            armed[i] = tel.heartbeat.armed
        if tel.status is not None and tel.status.battery_remaining_pct is not None:
            battery[i] = tel.status.battery_remaining_pct
        modes.append(profile.mode_text(tel.heartbeat))
    return FleetState(t=now, ids=tuple(ids), p_ned=p, v_ned=v, yaw=yaw, tilt=tilt, age=age,
                      heartbeat_age=hb_age, armed=armed, battery=battery, modes=tuple(modes))
