"""Massless rope between a vehicle's centre of mass and the payload.

A stiff spring-damper in extension only: no force while the rope is shorter
than its length (slack), and the damping term may reduce the tension but never
makes it negative, so a rope can pull but never push.
"""

from __future__ import annotations

import math

from gcs.common import kernel

__all__ = ["rope_tension"]


@kernel()
def rope_tension(dx: float, dy: float, dz: float, dvx: float, dvy: float, dvz: float,
                 length: float, stiffness: float, damping: float
                 ) -> tuple[float, float, float, float]:
    """Tension (N) and unit vector from payload to vehicle.

    ``d`` is vehicle minus payload position (m) and ``dv`` the same for velocity
    (m/s). The rope pulls the payload by ``+tension * u`` and the vehicle by
    ``-tension * u``.
    """
    dist = math.sqrt(dx * dx + dy * dy + dz * dz)
    stretch = dist - length
    if stretch <= 0.0 or dist == 0.0:
        return 0.0, 0.0, 0.0, 0.0
    ux, uy, uz = dx / dist, dy / dist, dz / dist
    stretch_rate = dvx * ux + dvy * uy + dvz * uz
    tension = max(0.0, stiffness * stretch + damping * stretch_rate)
    return tension, ux, uy, uz
