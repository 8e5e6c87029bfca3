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
    """Snapshot every vehicle's telemetry at loop time ``now``.

    Plain Python lists are filled and turned into arrays once: element-wise
    writes into numpy arrays cost more than the rest of the loop.
    """
    nan3 = (math.nan, math.nan, math.nan)
    p: list[tuple[float, float, float]] = []
    v: list[tuple[float, float, float]] = []
    yaw: list[float] = []
    tilt: list[float] = []
    age: list[float] = []
    hb_age: list[float] = []
    armed: list[bool] = []
    battery: list[float] = []
    modes: list[str] = []
    for vid in ids:
        profile = profiles[vid]
        tel = profile.link.telemetry
        position = tel.position
        if position is not None:
            p.append(position.p_ned)
            v.append(position.v_ned)
            age.append(max(0.0, now - position.received_at))
        else:
            p.append(nan3)
            v.append(nan3)
            age.append(math.inf)
        attitude = tel.attitude
        if attitude is not None:
            roll, pitch, heading = attitude.rpy
            yaw.append(heading)
            tilt.append(math.acos(max(-1.0, min(1.0, math.cos(roll) * math.cos(pitch)))))
        else:
            yaw.append(0.0)
            tilt.append(math.nan)
        hb = tel.heartbeat
        hb_age.append(math.inf if hb is None else max(0.0, now - hb.received_at))
        armed.append(hb is not None and hb.armed)
        status = tel.status
        remaining = None if status is None else status.battery_remaining_pct
        battery.append(math.nan if remaining is None else remaining)
        modes.append(profile.mode_text(hb))
    n = len(ids)
    return FleetState(t=now, ids=tuple(ids), p_ned=np.array(p, dtype=float).reshape(n, 3),
                      v_ned=np.array(v, dtype=float).reshape(n, 3), yaw=np.array(yaw, dtype=float),
                      tilt=np.array(tilt, dtype=float), age=np.array(age, dtype=float),
                      heartbeat_age=np.array(hb_age, dtype=float),
                      armed=np.array(armed, dtype=bool), battery=np.array(battery, dtype=float),
                      modes=tuple(modes))
