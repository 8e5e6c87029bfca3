"""Incremental nonlinear dynamic inversion (INDI) laws of the paper's section IV.

Acceleration INDI, eq. (inca): an increment ``Δu = m G⁻¹(ν_a − a_f)`` of
``u = [φ, θ, T]`` from the filtered acceleration error, where ``G`` is the
paper's matrix of partial derivatives of the thrust vector ``T R(η) e_z``.
As in the paper (and Smeur et al. 2018) ``T`` is the thrust along +z_body, so
it is negative when the rotors push up; callers pass ``-thrust``.

Attitude INDI: rotor thrust increments that produce an angular-acceleration
increment, through the inverse of the control effectiveness matrix.

Both laws take and return floats so the kernel calls them without allocating.
"""

from __future__ import annotations

import math

import numpy as np

from gcs.common import kernel

__all__ = ["acceleration_increment", "g_matrix", "rotor_thrust_increment"]


@kernel()
def g_matrix(phi: float, theta: float, psi: float, thrust_z: float) -> tuple[
        float, float, float, float, float, float, float, float, float]:
    """The paper's G(η, T) row-major: d(T R(η) e_z)/d[φ, θ, T], with T along +z_body."""
    cf, sf = math.cos(phi), math.sin(phi)
    ct, st = math.cos(theta), math.sin(theta)
    cp, sp = math.cos(psi), math.sin(psi)
    t = thrust_z
    return (t * (cf * sp - sf * cp * st), t * cf * cp * ct, sf * sp + cf * cp * st,
            -t * (sf * sp * st + cf * cp), t * cf * sp * ct, cf * sp * st - sf * cp,
            -t * ct * sf, -t * st * cf, cf * ct)


@kernel()
def acceleration_increment(phi: float, theta: float, psi: float, thrust_z: float, mass: float,
                           ex: float, ey: float, ez: float) -> tuple[float, float, float]:
    """Eq. (inca): Δ[φ, θ, T] = m G⁻¹ e for an acceleration error e (NED, m/s^2).

    Solved with the adjugate; G is invertible while T ≠ 0 and |θ| < 90°.
    """
    g00, g01, g02, g10, g11, g12, g20, g21, g22 = g_matrix(phi, theta, psi, thrust_z)
    c00 = g11 * g22 - g12 * g21
    c01 = g12 * g20 - g10 * g22
    c02 = g10 * g21 - g11 * g20
    det = g00 * c00 + g01 * c01 + g02 * c02
    k = mass / det
    d_phi = k * (c00 * ex + (g02 * g21 - g01 * g22) * ey + (g01 * g12 - g02 * g11) * ez)
    d_theta = k * (c01 * ex + (g00 * g22 - g02 * g20) * ey + (g02 * g10 - g00 * g12) * ez)
    d_thrust = k * (c02 * ex + (g01 * g20 - g00 * g21) * ey + (g00 * g11 - g01 * g10) * ez)
    return d_phi, d_theta, d_thrust


@kernel()
def rotor_thrust_increment(effectiveness_inv: np.ndarray, inertia: np.ndarray,
                           d_alpha_x: float, d_alpha_y: float, d_alpha_z: float,
                           d_thrust: float) -> tuple[float, float, float, float]:
    """Rotor thrust increments (N) for an angular-acceleration increment (rad/s^2) and a
    total-thrust increment (N): B⁻¹ [J Δα; ΔT]."""
    v0 = inertia[0] * d_alpha_x
    v1 = inertia[1] * d_alpha_y
    v2 = inertia[2] * d_alpha_z
    b = effectiveness_inv
    return (b[0, 0] * v0 + b[0, 1] * v1 + b[0, 2] * v2 + b[0, 3] * d_thrust,
            b[1, 0] * v0 + b[1, 1] * v1 + b[1, 2] * v2 + b[1, 3] * d_thrust,
            b[2, 0] * v0 + b[2, 1] * v1 + b[2, 2] * v2 + b[2, 3] * d_thrust,
            b[3, 0] * v0 + b[3, 1] * v1 + b[3, 2] * v2 + b[3, 3] * d_thrust)
