"""Equations of motion of the world: one physics step of every vehicle and the payload.

Rotor speeds follow their commands with a first-order lag; each rotor pushes
``k_f ω²`` along -z_body and twists the body by ``-spin * torque_ratio * thrust``.
Add the rope pull (at the centre of mass, so no torque), linear drag against
the wind and ground contact at the four rotor points, then integrate with
semi-implicit Euler (velocity first, then position; body rate first, then the
exact quaternion rotation), which does not pump energy into oscillations.
The payload is a point mass pulled by the ropes, slowed by linear drag and held
by the ground. Every body uses the others' state from the start of the step.

One function does the whole step: numba charges for passing the state
NamedTuples on every call (figures: docs/performance.md, "Why it is fast"), so
the per-step work is not split into per-vehicle calls.
"""

from __future__ import annotations

import numpy as np

from gcs.common import kernel
from sim._ground import contact_force
from sim._ropes import rope_tension
from sim._state import PhysicsParams, PhysicsState
from sim._wind import gust_step
from vehicles import quat_integrate, quat_to_rotation

__all__ = ["physics_step"]


@kernel()
def physics_step(s: PhysicsState, prm: PhysicsParams, cmd: np.ndarray,
                 gust_noise: np.ndarray) -> None:
    """Advance the world by ``prm.dt`` with rotor speed commands ``cmd`` (N, 4) rad/s;
    ``gust_noise`` (3,) is the unit normal draw that drives the gust."""
    dt = prm.dt
    gust_step(s.gust_ned, prm.gust_decay, prm.gust_drive, gust_noise)
    wind = (prm.wind_mean[0] + s.gust_ned[0], prm.wind_mean[1] + s.gust_ned[1],
            prm.wind_mean[2] + s.gust_ned[2])
    payload_p = (s.payload_p_ned[0], s.payload_p_ned[1], s.payload_p_ned[2])
    payload_v = (s.payload_v_ned[0], s.payload_v_ned[1], s.payload_v_ned[2])
    # Forces on the payload: drag now, rope pulls added per vehicle.
    lfx = -prm.payload_drag * (payload_v[0] - wind[0])
    lfy = -prm.payload_drag * (payload_v[1] - wind[1])
    lfz = -prm.payload_drag * (payload_v[2] - wind[2])
    for i in range(s.p_ned.shape[0]):
        # Rotors: first-order speed lag, thrust and drag torque.
        thrust = 0.0
        tx = ty = tz = 0.0
        for j in range(4):
            w_cmd = min(prm.rotor_speed_max, max(0.0, cmd[i, j]))
            w = s.rotor_speed[i, j] + prm.rotor_alpha * (w_cmd - s.rotor_speed[i, j])
            s.rotor_speed[i, j] = w
            t_j = prm.thrust_coefficient * w * w
            thrust += t_j
            tx -= prm.rotor_xy[j, 1] * t_j
            ty += prm.rotor_xy[j, 0] * t_j
            tz -= prm.rotor_spin[j] * prm.torque_ratio * t_j

        qw, qx, qy, qz = s.q_wxyz[i, 0], s.q_wxyz[i, 1], s.q_wxyz[i, 2], s.q_wxyz[i, 3]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_to_rotation(qw, qx, qy, qz)
        px, py, pz = s.p_ned[i, 0], s.p_ned[i, 1], s.p_ned[i, 2]
        vx, vy, vz = s.v_ned[i, 0], s.v_ned[i, 1], s.v_ned[i, 2]
        wx, wy, wz = s.omega_body[i, 0], s.omega_body[i, 1], s.omega_body[i, 2]

        # Non-gravitational forces in NED: thrust, rope, drag.
        fx = -thrust * r02
        fy = -thrust * r12
        fz = -thrust * r22
        tension, ux, uy, uz = rope_tension(px - payload_p[0], py - payload_p[1], pz - payload_p[2],
                                           vx - payload_v[0], vy - payload_v[1], vz - payload_v[2],
                                           prm.rope_length[i], prm.rope_stiffness, prm.rope_damping)
        s.rope_tension[i] = tension
        fx -= tension * ux + prm.drag_coefficient * (vx - wind[0])
        fy -= tension * uy + prm.drag_coefficient * (vy - wind[1])
        fz -= tension * uz + prm.drag_coefficient * (vz - wind[2])

        # Ground contact at the rotor points (body z = 0).
        for j in range(4):
            bx, by = prm.rotor_xy[j, 0], prm.rotor_xy[j, 1]
            depth = pz + r20 * bx + r21 * by - prm.ground_z
            if depth <= 0.0:
                continue
            cx, cy, cz = -wz * by, wz * bx, wx * by - wy * bx  # omega x r in body
            gx, gy, gz = contact_force(
                depth, vx + r00 * cx + r01 * cy + r02 * cz, vy + r10 * cx + r11 * cy + r12 * cz,
                vz + r20 * cx + r21 * cy + r22 * cz, prm.ground_stiffness, prm.ground_damping,
                prm.friction_coefficient, prm.friction_damping)
            fx += gx
            fy += gy
            fz += gz
            gbx = r00 * gx + r10 * gy + r20 * gz
            gby = r01 * gx + r11 * gy + r21 * gz
            gbz = r02 * gx + r12 * gy + r22 * gz
            tx += by * gbz
            ty -= bx * gbz
            tz += bx * gby - by * gbx

        inv_m = 1.0 / prm.mass
        s.specific_force_body[i, 0] = (r00 * fx + r10 * fy + r20 * fz) * inv_m
        s.specific_force_body[i, 1] = (r01 * fx + r11 * fy + r21 * fz) * inv_m
        s.specific_force_body[i, 2] = (r02 * fx + r12 * fy + r22 * fz) * inv_m

        # Semi-implicit Euler.
        vx += fx * inv_m * dt
        vy += fy * inv_m * dt
        vz += (fz * inv_m + prm.gravity) * dt
        s.v_ned[i, 0], s.v_ned[i, 1], s.v_ned[i, 2] = vx, vy, vz
        s.p_ned[i, 0] = px + vx * dt
        s.p_ned[i, 1] = py + vy * dt
        s.p_ned[i, 2] = pz + vz * dt
        jx, jy, jz = prm.inertia[0], prm.inertia[1], prm.inertia[2]
        wx_new = wx + (tx - (jz - jy) * wy * wz) / jx * dt
        wy_new = wy + (ty - (jx - jz) * wz * wx) / jy * dt
        wz_new = wz + (tz - (jy - jx) * wx * wy) / jz * dt
        s.omega_body[i, 0], s.omega_body[i, 1], s.omega_body[i, 2] = wx_new, wy_new, wz_new
        s.q_wxyz[i, 0], s.q_wxyz[i, 1], s.q_wxyz[i, 2], s.q_wxyz[i, 3] = quat_integrate(
            qw, qx, qy, qz, wx_new, wy_new, wz_new, dt)
        lfx += tension * ux
        lfy += tension * uy
        lfz += tension * uz

    gx, gy, gz = contact_force(payload_p[2] - prm.ground_z, payload_v[0], payload_v[1],
                               payload_v[2], prm.ground_stiffness, prm.ground_damping,
                               prm.friction_coefficient, prm.friction_damping)
    inv_m = 1.0 / prm.payload_mass
    s.payload_v_ned[0] = payload_v[0] + (lfx + gx) * inv_m * dt
    s.payload_v_ned[1] = payload_v[1] + (lfy + gy) * inv_m * dt
    s.payload_v_ned[2] = payload_v[2] + ((lfz + gz) * inv_m + prm.gravity) * dt
    for k in range(3):
        s.payload_p_ned[k] = payload_p[k] + s.payload_v_ned[k] * dt
    s.step[0] += 1
