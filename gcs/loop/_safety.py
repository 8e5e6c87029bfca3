"""Safety rules of the GCS loop, each enforced here and nowhere else.

Every tick the loop asks :func:`evaluate` what the team may do:

* telemetry of a vehicle older than ``stale_after`` (0.5 s): the motion
  freezes (shape kept, disagreements zero) and the vehicle is reported;
* a vehicle silent for ``land_after``: the whole team lands;
* a vehicle farther from the team's centroid than the analysis' safe bound
  (beyond it the ropes pull harder than the horizontal force left at the bank
  limit minus the largest commanded acceleration): the team holds, each
  vehicle on its own point (the shape-keeping terms would amplify a
  deformation the GCS cannot trust, as with positions in disagreeing frames),
  and lands if the deformation keeps growing (the loop tracks the growth);
* while the team flies on the GCS's setpoints, a vehicle that left the mode
  that flies them (a failsafe, a pilot's switch, a lost setpoint stream): the
  motion freezes, since the rest of the team would drag it by the ropes; one
  that comes down on its own (a landing mode, or disarmed) lands the team,
  which cannot hold the payload without it.

The geofence lives in :mod:`gcs.loop._geofence` (it limits the motion rather
than stopping it), acceleration saturation in :func:`gcs.guidance._law.saturate`,
the bank limit on board the vehicles. An unknown vehicle state (NaN) never raises here: it is
reported as stale.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gcs.common import kernel
from gcs.config import SafetyConfig

__all__ = ["SafetyEvent", "SafetyReason", "SafetyVerdict", "evaluate", "rule_flags"]


class SafetyReason(enum.Enum):
    """Why the motion was frozen or the team sent to land."""

    STALE = "telemetry is stale"
    LOST = "link lost"
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

    freeze: bool  # the operator's motion stops (the shape is kept)
    land: bool
    events: tuple[SafetyEvent, ...]
    hold: bool = False  # each vehicle holds its own point (deformed beyond the safe bound)
    deformation: float = float("nan")  # largest distance from the centroid, m (NaN: unknown)


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
    # Flags over the whole team in one compiled pass, then a loop over the offenders
    # only: the loop runs every tick for up to a hundred vehicles, and nearly always
    # finds none (as numpy masks, a sizeable part of the 4 Hz tick: docs/performance.md).
    age, p_ned = np.asarray(age, dtype=float), np.asarray(p_ned, dtype=float)
    r = np.empty(len(age))
    flags = rule_flags(age, p_ned, cfg.land_after, cfg.stale_after, safe_radius, r)
    if not flags.any() and not modes:  # nearly every tick: no rule to look further at
        return _OK
    land = False
    for i in np.flatnonzero(flags & (LOST | STALE)).tolist():
        vid = ids[i]
        if flags[i] & LOST:
            land = True
            events.append(SafetyEvent(SafetyReason.LOST, vid,
                                      f"vehicle {vid}: {_silent(age[i])}: landing the team"))
        else:
            events.append(SafetyEvent(SafetyReason.STALE, vid,
                                      f"vehicle {vid}: {_silent(age[i])}: motion frozen"))
    deformed = np.flatnonzero(flags & DEFORMED).tolist()
    for i in deformed:
        vid = ids[i]
        events.append(SafetyEvent(SafetyReason.DEFORMATION, vid,
                                  f"vehicle {vid}: {r[i]:.2f} m from the centroid, "
                                  f"safe bound {safe_radius:.2f} m: holding (each vehicle "
                                  f"on its own point)"))
    for i, (mode, want) in enumerate(zip(modes, expected, strict=True)):
        if mode == want or flags[i] & STALE:  # a silent vehicle is reported as such, above
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
    return SafetyVerdict(freeze=True, land=land, events=tuple(events), hold=bool(deformed),
                         deformation=float(np.nanmax(r)) if deformed else float("nan"))


LOST, STALE, DEFORMED = 1, 2, 4
"""Bits of :func:`rule_flags`, one per rule that looks at the telemetry alone."""


@kernel()
def rule_flags(age: np.ndarray, p_ned: np.ndarray, land_after: float, stale_after: float,
               safe_radius: float, r: np.ndarray) -> np.ndarray:
    """Which of the telemetry rules each vehicle breaks, as bits (n,) int64.

    ``age`` (n,) s, ``p_ned`` (n, 3) m as :func:`evaluate` takes them. LOST:
    silent beyond ``land_after`` (never heard counts); STALE: position older
    than ``stale_after`` or unknown (NaN); DEFORMED: farther than ``safe_radius`` from
    the team's centroid, judged only when every vehicle is fresh (the centroid
    of a partly known team means nothing). ``r`` receives the distances from
    the centroid (NaN when not judged).
    """
    n = len(age)
    flags = np.zeros(n, np.int64)
    fresh_all = n > 0
    for i in range(n):
        x, y, z = p_ned[i, 0], p_ned[i, 1], p_ned[i, 2]
        known = math.isfinite(x) and math.isfinite(y) and math.isfinite(z)
        if age[i] > land_after:
            flags[i] |= LOST
        if not (math.isfinite(age[i]) and age[i] <= stale_after and known):
            flags[i] |= STALE
            fresh_all = False
    r[:] = np.nan
    if fresh_all:
        cx = cy = 0.0
        for i in range(n):
            cx += p_ned[i, 0]
            cy += p_ned[i, 1]
        cx, cy = cx / n, cy / n
        for i in range(n):
            r[i] = math.hypot(p_ned[i, 0] - cx, p_ned[i, 1] - cy)
            if r[i] > safe_radius:
                flags[i] |= DEFORMED
    return flags


def _silent(seconds: float) -> str:
    if not np.isfinite(seconds):
        return "never heard from"
    return f"no fresh telemetry for {seconds:.2f} s"
