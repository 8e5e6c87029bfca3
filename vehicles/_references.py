"""Acceleration references nu_a of the autopilot's own modes.

OFFBOARD takes nu_a from the setpoint (with eq. (pdalt) when only the altitude
is given); HOLD, TAKEOFF and LAND close position loops here. All are PD laws
whose output is an acceleration, because the acceleration INDI below them
makes the vehicle a double integrator.
"""

from __future__ import annotations

from gcs.common import kernel

__all__ = ["altitude_pd", "climb_ramp", "position_hold"]


@kernel()
def altitude_pd(z_ned: float, vz_ned: float, z_sp_ned: float, vz_ref: float,
                kp: float, kv: float) -> float:
    """Eq. (pdalt): nu_az = k_p (z_sp - z) + k_v (vz_ref - v_z), NED, m/s^2.

    The paper writes k_p (p_z - p_zd) - k_v v_z; with positive gains and z down
    the position error must enter with this sign for the loop to be stable.
    ``vz_ref`` is zero except on TAKEOFF's climb ramp.
    """
    return kp * (z_sp_ned - z_ned) + kv * (vz_ref - vz_ned)


@kernel()
def position_hold(px: float, py: float, vx: float, vy: float, hold_x: float, hold_y: float,
                  kp: float, kv: float) -> tuple[float, float]:
    """Horizontal PD towards a held point, m/s^2."""
    return kp * (hold_x - px) - kv * vx, kp * (hold_y - py) - kv * vy


@kernel()
def climb_ramp(z_ref: float, z_target: float, rate: float, dt: float) -> float:
    """Move a z reference towards its target by at most ``rate * dt`` (m)."""
    step = rate * dt
    return min(z_ref + step, max(z_ref - step, z_target))
