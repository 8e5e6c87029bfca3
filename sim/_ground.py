"""Penalty contact with flat ground for one point (a rotor's footprint or the payload).

A spring-damper normal force that only pushes up, and a tangential force that
resists sliding: viscous at low speed, capped by Coulomb friction. This keeps
vehicles and payload still on the ground without a separate "landed" state.
"""

from __future__ import annotations

import math

from gcs.common import kernel

__all__ = ["contact_force"]


@kernel()
def contact_force(depth: float, vx: float, vy: float, vz: float, stiffness: float,
                  damping: float, friction_coefficient: float, friction_damping: float
                  ) -> tuple[float, float, float]:
    """NED force (N) on a point ``depth`` m below the ground moving at ``v`` (m/s)."""
    if depth <= 0.0:
        return 0.0, 0.0, 0.0
    normal = max(0.0, stiffness * depth + damping * vz)
    fx = -friction_damping * vx
    fy = -friction_damping * vy
    tangential = math.sqrt(fx * fx + fy * fy)
    bound = friction_coefficient * normal
    if tangential > bound:
        scale = bound / tangential
        fx *= scale
        fy *= scale
    return fx, fy, -normal
