"""The gains of a hold: a vehicle pulled back to a point by acceleration, critically damped.

Why one pair: the GCS loop holds a team that it cannot trust to keep its shape
(gcs.loop), and the PX4 take-off stream holds each vehicle while it climbs
(gcs.link); the two are the same hold and must not drift apart.
"""

from __future__ import annotations

__all__ = ["HOLD_KP", "HOLD_KV"]

HOLD_KP, HOLD_KV = 0.25, 1.0
"""Pull back to the held point, 1/s^2, and velocity damping, 1/s: critically damped
(KV^2 = 4 KP), slow beside the 4 Hz tick."""
