"""The scales of the shape the GCS flies: within the safe span, and not so small that the
payload, accelerating, loads one vehicle to its reference thrust.

Why here: a shrunk shape hangs the payload from steeper ropes, a grown one leans them
further; the certificate holds only over the scales flown, and the GCS caps the scale
in flight with these (:func:`gcs.analysis.safe_guidance`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from gcs.analysis._static_load import NoHangingPointError
from gcs.analysis._team_load import accelerating_share
from gcs.config import Team

__all__ = ["SmallestScale", "flown_scale_max", "flown_scale_min"]


def flown_scale_max(team: Team, safe_span: float) -> float:
    """The largest scale the GCS flies: ``guidance.scale_max`` capped inside the safe span
    (4 % short of it, never below 1): 2 % for the distance errors and the payload's swing,
    2 % for the overshoot of a growing shape, which the distance term alone brings to the
    new scale (the square overshot by 3 % of its radius at ``operator.scale_rate`` 0.1/s
    and flew 2 cm beyond the safe span with the cap at 2 %)."""
    guidance = team.config.guidance
    radius = float(team.formation.radii.max())
    safe = 0.5 * safe_span / radius if radius > 0 else math.inf
    return guidance.scale_max if safe >= guidance.scale_max else max(1.0, 0.96 * safe)


class SmallestScale(NamedTuple):
    """The smallest scale flown, and why not smaller."""

    scale: float
    share_at_scale_min: float
    """The accelerating share at ``guidance.scale_min`` (inf: the ropes cannot hang it)."""


def flown_scale_min(team: Team) -> SmallestScale:
    """The smallest scale the GCS flies: ``guidance.scale_min`` raised (never above 1) until
    the payload, accelerating at ``limits.accel_norm``, loads no vehicle up to the reference
    thrust (85 % of its capacity).

    A shrunk shape hangs the payload from steeper ropes, which let it swing towards the
    side it accelerates to: the paper's square at half size puts 0.667 of the payload on
    one vehicle at its acceleration limit (0.386 at scale 1), and at 0.3 all of it, beyond
    the Bebop's full thrust. The share falls as the scale grows (bisection, to 0.005).
    """
    cfg = team.config
    mass, load_max = cfg.airframe.mass, cfg.airframe.thrust_reference
    g, payload, accel = cfg.analysis.gravity, cfg.payload.mass, cfg.limits.accel_norm

    def share(scale: float, directions: np.ndarray | None = None) -> float:
        try:
            return accelerating_share(team, accel, (scale,), directions).share
        except NoHangingPointError:
            return math.inf

    def flown(scale: float, directions: np.ndarray | None = None) -> bool:
        return (mass + payload * share(scale, directions)) * g < load_max

    low = cfg.guidance.scale_min
    at_min = share(low)
    if (mass + payload * at_min) * g < load_max:
        return SmallestScale(low, at_min)
    try:  # the worst direction barely turns with the scale: search near it, then check all
        worst = accelerating_share(team, accel).direction
    except NoHangingPointError:
        return SmallestScale(1.0, at_min)
    near = worst + np.radians(np.arange(-10.0, 10.5, 5.0))
    high = 1.0
    if not flown(high, near):
        return SmallestScale(1.0, at_min)  # the share at scale 1 is the accelerating warning
    while high - low > 0.005:
        mid = 0.5 * (low + high)
        low, high = (low, mid) if flown(mid, near) else (mid, high)
    smallest = math.ceil(high * 1000.0) / 1000.0
    while smallest < 1.0 and not flown(smallest):  # another direction is worse there
        smallest = min(1.0, smallest + 0.005)
    return SmallestScale(smallest, at_min)
