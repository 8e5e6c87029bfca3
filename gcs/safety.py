"""Safety rules of the GCS loop, each enforced here and nowhere else.

Every tick the loop asks :func:`evaluate` what the team may do:

* telemetry of a vehicle older than ``stale_after`` (0.5 s): the motion
  freezes (shape kept, disagreements zero) and the vehicle is reported;
* a vehicle silent for ``land_after``: the whole team lands;
* a vehicle outside the geofence (horizontal box or ceiling): the motion freezes;
* a vehicle farther from the team's centroid than the analysis' safe bound
  (beyond it the ropes pull harder than the horizontal force left at the bank
  limit minus the largest commanded acceleration): the motion freezes;
* while the team flies on the GCS's setpoints, a vehicle that left the mode
  that flies them (a failsafe, a pilot's switch, a lost setpoint stream): the
  motion freezes, since the rest of the team would drag it by the ropes; one
  that comes down on its own (a landing mode, or disarmed) lands the team,
  which cannot hold the payload without it.

Acceleration saturation lives in :func:`gcs.guidance.saturate`, the bank limit
on board the vehicles. An unknown vehicle state (NaN) never raises here: it is
reported as stale.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gcs.config import SafetyConfig

__all__ = ["SafetyEvent", "SafetyReason", "SafetyVerdict", "evaluate"]


class SafetyReason(enum.Enum):
    """Why the motion was frozen or the team sent to land."""

    STALE = "telemetry is stale"
    LOST = "link lost"
    GEOFENCE = "outside the geofence"
    DEFORMATION = "deformed beyond the safe bound"
    MODE = "left the GCS's mode"
    COMING_DOWN = "coming down on its own"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class SafetyEvent:
    """One rule that fired for one vehicle."""

    reason: SafetyReason
    vehicle: int
    text: str


@dataclass(frozen=True)
class SafetyVerdict:
    """What the team may do this tick."""

    freeze: bool
    land: bool
    events: tuple[SafetyEvent, ...]


_OK = SafetyVerdict(freeze=False, land=False, events=())


def evaluate(cfg: SafetyConfig, ids: Sequence[int], age: np.ndarray, p_ned: np.ndarray, *,
             safe_radius: float, modes: Sequence[str] = (), expected: Sequence[str] = (),
             coming_down: np.ndarray | None = None) -> SafetyVerdict:
    """Apply every rule to the team's latest state.

    Args:
        cfg: the rules' thresholds.
        ids: vehicle system ids, in formation order.
        age: (n,) age of each vehicle's latest position, s (inf if never heard).
        p_ned: (n, 3) latest NED positions, m (NaN where unknown).
        safe_radius: largest horizontal distance of a vehicle from the team's
            centroid (the analysis' safe span / 2), m.
        modes: each vehicle's flight mode while the team flies on the GCS's
            setpoints; empty otherwise (the mode rule does not apply).
        expected: each vehicle's mode that flies those setpoints (with ``modes``).
        coming_down: (n,) True where a vehicle is in a landing mode or disarmed
            (with ``modes``).
    """
    events: list[SafetyEvent] = []
    # Masks over the whole team, then a loop over the offenders only: the loop runs
    # every tick for up to a hundred vehicles, and nearly always finds none.
    known = np.all(np.isfinite(p_ned), axis=1)
    lost = age > cfg.land_after
    fresh = np.isfinite(age) & (age <= cfg.stale_after) & known
    for i in np.flatnonzero(lost | ~fresh):
        vid = ids[i]
        if lost[i]:
            events.append(SafetyEvent(SafetyReason.LOST, vid,
                                      f"vehicle {vid}: {_silent(age[i])}: landing the team"))
        else:
            events.append(SafetyEvent(SafetyReason.STALE, vid,
                                      f"vehicle {vid}: {_silent(age[i])}: motion frozen"))
    with np.errstate(invalid="ignore"):  # NaN rows are not fresh and never compared
        outside = fresh & ((np.abs(p_ned[:, :2]).max(axis=1) > cfg.geofence_xy)
                           | (-p_ned[:, 2] > cfg.geofence_altitude))
    for i in np.flatnonzero(outside):
        vid, (x, y, z) = ids[i], p_ned[i]
        events.append(SafetyEvent(SafetyReason.GEOFENCE, vid,
                                  f"vehicle {vid}: at ({x:.2f}, {y:.2f}, {-z:.2f}) m, "
                                  f"outside the geofence: motion frozen"))
    if fresh.size and fresh.all():
        xy = p_ned[:, :2]
        r = np.linalg.norm(xy - xy.mean(axis=0), axis=1)
        for i in np.flatnonzero(r > safe_radius):
            vid = ids[i]
            events.append(SafetyEvent(SafetyReason.DEFORMATION, vid,
                                      f"vehicle {vid}: {r[i]:.2f} m from the centroid, "
                                      f"safe bound {safe_radius:.2f} m: motion frozen"))
    land = bool(lost.any())
    for i, (mode, want) in enumerate(zip(modes, expected, strict=True)):
        if mode == want or not fresh[i]:  # a silent vehicle is reported as such, above
            continue
        vid = ids[i]
        if coming_down is not None and coming_down[i]:
            land = True
            events.append(SafetyEvent(SafetyReason.COMING_DOWN, vid,
                                      f"vehicle {vid}: coming down on its own ({mode}): "
                                      f"landing the team"))
        else:
            events.append(SafetyEvent(SafetyReason.MODE, vid, f"vehicle {vid}: in {mode}, not "
                                      f"{want}: motion frozen"))
    if not events:
        return _OK
    return SafetyVerdict(freeze=True, land=land, events=tuple(events))


def _silent(seconds: float) -> str:
    if not np.isfinite(seconds):
        return "never heard from"
    return f"no fresh telemetry for {seconds:.2f} s"
