"""Quaternion and Euler-angle helpers shared by the autopilot and the physics.

Quaternions are ``q_wxyz`` (scalar first) and rotate body FRD vectors into the
NED frame (``R_ned_body``). Euler angles are the aerospace ZYX sequence
(yaw, then pitch, then roll), as in the paper's G matrix. The helpers take and
return plain floats so the numba kernels call them without allocating.
"""

from __future__ import annotations

import math

import numpy as np

from gcs.common import kernel

__all__ = [
    "euler_from_quaternions",
    "euler_to_quat",
    "quat_integrate",
    "quat_multiply",
    "quat_to_euler",
    "quat_to_rotation",
]


@kernel()
def quat_multiply(aw: float, ax: float, ay: float, az: float,
                  bw: float, bx: float, by: float, bz: float) -> tuple[float, float, float, float]:
    """Hamilton product a ⊗ b."""
    return (aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw)


@kernel()
def quat_to_rotation(w: float, x: float, y: float, z: float) -> tuple[
        float, float, float, float, float, float, float, float, float]:
    """Rotation matrix R_ned_body of a unit quaternion, row-major (r00, r01, ..., r22)."""
    return (1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y),
            2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x),
            2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y))


@kernel()
def quat_integrate(w: float, x: float, y: float, z: float,
                   wx: float, wy: float, wz: float, dt: float) -> tuple[float, float, float, float]:
    """Attitude after rotating for ``dt`` at body rate (wx, wy, wz) rad/s: q ⊗ exp(ω dt / 2).

    Exact for a constant rate, and renormalised so rounding never accumulates.
    """
    angle = math.sqrt(wx * wx + wy * wy + wz * wz) * dt
    if angle > 1e-12:
        s = math.sin(0.5 * angle) * dt / angle
        c = math.cos(0.5 * angle)
    else:
        s = 0.5 * dt
        c = 1.0
    rw, rx, ry, rz = quat_multiply(w, x, y, z, c, wx * s, wy * s, wz * s)
    norm = math.sqrt(rw * rw + rx * rx + ry * ry + rz * rz)
    return rw / norm, rx / norm, ry / norm, rz / norm


@kernel()
def quat_to_euler(w: float, x: float, y: float, z: float) -> tuple[float, float, float]:
    """Roll, pitch, yaw (ZYX), rad."""
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    sin_pitch = min(1.0, max(-1.0, 2.0 * (w * y - z * x)))
    pitch = math.asin(sin_pitch)
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, pitch, yaw


@kernel()
def euler_to_quat(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """Unit quaternion of ZYX Euler angles, rad."""
    cr, sr = math.cos(0.5 * roll), math.sin(0.5 * roll)
    cp, sp = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    cy, sy = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    return (cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy)


@kernel()
def euler_from_quaternions(q_wxyz: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (N, 3) in rad of a batch of quaternions (N, 4), e.g. for telemetry."""
    out = np.empty((q_wxyz.shape[0], 3))
    for i in range(q_wxyz.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = quat_to_euler(
            q_wxyz[i, 0], q_wxyz[i, 1], q_wxyz[i, 2], q_wxyz[i, 3])
    return out
