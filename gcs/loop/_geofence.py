"""The geofence, enforced here and nowhere else: the team slows to a stop at it and can fly back.

The fence is a horizontal box of half-size ``safety.geofence_xy`` about the
team origin and a ceiling at ``safety.geofence_altitude``. Freezing every stick
at the fence would leave a team that reaches it no way back, and a team
reaches it within seconds of any free flight: with the paper's velocity
gain ``c1`` the team follows a speed demand with a time constant of ``1/c1``
(about 6 s), so it coasts for metres after the sticks centre.

So the rule acts on where the team would stop, not where it is. For the
team's centroid, eq. udi gives ``a = c1 (u - v)`` (the shape terms cancel
over the team), so the stopping point ``s = x + v / c1`` moves exactly with
the commanded velocity: ``ds/dt = u``. Per side of the box, the outward part
of the commanded velocity is limited to ``max_speed (L - h - s) / h``, where
``s`` is the stopping point of the team's outermost point (a vehicle, or the
payload when its position is known), ``L`` the fence and ``h`` half the
margin: full speed until the stopping point enters the margin, zero half way
through it, and inwards (at most half the top speed) beyond that, which
brings back a team the wind pushed out (a steady push only moves the point
where it stops towards the fence).
Only the outward part is cut: every stick that points back in works. A
rotation is slowed by the same factor as the tightest side (it swings the
outer vehicles outward).

The ceiling: the altitude setpoint never exceeds it, and a vehicle above it is
reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs.config import SafetyConfig
from gcs.guidance import MotionDemand

__all__ = ["RETURN_FRACTION", "FenceVerdict", "fence_demand"]

RETURN_FRACTION = 0.5
"""Fastest speed at which the fence brings a team back inside, as a fraction of the top speed."""

_SIDES = (("north", 0, 1.0), ("south", 0, -1.0), ("east", 1, 1.0), ("west", 1, -1.0))


@dataclass(frozen=True)
class FenceVerdict:
    """What the fence did to one tick's demand."""

    demand: MotionDemand
    near: tuple[str, ...]  # sides whose margin the team (or its stopping point) is in
    outside: tuple[str, ...]  # sides the team is beyond
    above: bool  # a vehicle is above the ceiling

    @property
    def text(self) -> str:
        """One line for the operator; empty when the fence did nothing."""
        if self.outside:
            return (f"outside the geofence ({', '.join(self.outside)}): "
                    "flying the team back in")
        if self.near:
            return (f"at the geofence ({', '.join(self.near)}): motion that way "
                    "slowed to stop at the fence")
        return ""


def fence_demand(cfg: SafetyConfig, demand: MotionDemand, *, heading: float | None,
                 points: np.ndarray, velocity: np.ndarray, altitude: np.ndarray,
                 max_speed: float, c1: float) -> FenceVerdict:
    """The operator's demand limited by the geofence.

    Args:
        cfg: the fence and its margin.
        demand: the operator's demand (team body frame).
        heading: the team's heading, rad (:func:`gcs.formation.fit_rotation`);
            None when the team cannot be placed, and the demand passes unchanged.
        points: (k, 2) known horizontal positions, m: every vehicle and the
            payload if known (NaN rows are ignored).
        velocity: (2,) the team's mean horizontal velocity, m/s.
        altitude: (n,) vehicle altitudes above the ground, m (NaN: unknown).
        max_speed: translation speed at full stick, m/s.
        c1: the guidance's velocity gain, 1/s (the team's speed time constant is 1/c1).
    """
    above = bool(np.any(np.nan_to_num(altitude, nan=-np.inf) > cfg.geofence_altitude))
    pts = points[np.isfinite(points).all(axis=1)]
    if heading is None or len(pts) == 0 or not np.isfinite(velocity).all():
        return FenceVerdict(demand, (), (), above)
    fwd = np.array([math.cos(heading), math.sin(heading)])
    right = np.array([-math.sin(heading), math.cos(heading)])
    u = max_speed * (demand.forward * fwd + demand.right * right)
    norm = float(np.hypot(*u))
    if norm > max_speed:  # as the guidance caps a diagonal stick
        u *= max_speed / norm
    taper = max(0.5 * cfg.geofence_margin, 0.05)  # m over which the speed goes to zero
    fence = cfg.geofence_xy
    near, outside, rotate_factor = [], [], 1.0
    for name, axis, sign in _SIDES:
        extent = float(np.max(sign * pts[:, axis]))
        stop = extent + sign * float(velocity[axis]) / c1
        room = fence - max(stop, extent)
        if extent > fence:
            outside.append(name)
        elif room < cfg.geofence_margin:
            near.append(name)
        allowed = max_speed * max(min((room - taper) / taper, 1.0), -RETURN_FRACTION)
        if sign * u[axis] > allowed:
            u[axis] = sign * allowed
        rotate_factor = min(rotate_factor, max((room - taper) / taper, 0.0))
    forward = float(np.clip(u @ fwd / max_speed, -1.0, 1.0))
    right_ = float(np.clip(u @ right / max_speed, -1.0, 1.0))
    rotate = demand.rotate * min(rotate_factor, 1.0)
    limited = MotionDemand(forward=forward, right=right_, rotate=rotate, scale=demand.scale)
    return FenceVerdict(limited, tuple(near), tuple(outside), above)
