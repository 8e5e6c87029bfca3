"""Rigid motions of the team synthesised as distance disagreements.

Following the paper (eqs. ``dis``, ``Av`` and Proposition 1), a vehicle's
desired velocity in steady state is a linear combination of the unit vectors of
its *own* edges, ``v*_i = sum_k A_v[i, k] zhat_k``; the coefficients are the
disagreements mu. For any rigid team we solve, per vehicle and per motion, the
least-norm combination that reproduces the rigid-body velocity field at the
desired shape (with three vehicles or more, the incident edges of a vertex of an
infinitesimally rigid framework always span the plane, so a solution exists):

* translation along the team's body x and along its body y (per 1 m/s),
* rotation about the centroid (per 1 rad/s).

A pair (two vehicles, one edge: rigid, but each vehicle has a single edge) can
only move along its edge: a motion some vehicle cannot make on its own edges is
left out (all zero) and named in :attr:`MotionBasis.unavailable`, rather than
flown in part (a pair across the team's x axis would otherwise drift along its
edge on a forward stick).

The centripetal term is Proposition 1's ``A_a = A_v D_(1/d) B^T A_v`` (the
derivative of ``v*`` along the rigid motion; with rotation alone it is the
paper's ``A_vr D B^T A_vr``, with translation too it also turns the translation
direction with the team, which the body-frame translation needs). ``A_a`` involves
edges two hops away, so it is re-expressed on each vehicle's own edges at the
desired shape: guidance stays local to a vehicle and its neighbours.

Scaling is done by scaling the desired distances ``d`` (as the seed's Paparazzi
implementation did): the shape converges to the scaled one through the distance
term, with no feed-forward. Unit vectors do not change with scale, so the
translation disagreements are scale-free; rotation disagreements per rad/s grow
with the scale, and the operator's rotation stick sets the disagreement (at most
``mu_r``), so a larger team spins more slowly, as in the seed.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from gcs.formation._graph import Formation

__all__ = [
    "MotionBasis",
    "centripetal_matrix",
    "edges_to_slots",
    "local_pseudoinverse",
    "motion_basis",
]


def local_pseudoinverse(formation: Formation) -> np.ndarray:
    """Per-vehicle least-norm map from a desired planar vector to slot coefficients.

    Returns P (n, S, 2): for vehicle i, ``alpha = P[i] @ w`` gives coefficients on
    its slots with ``sum_s alpha_s qhat_s = w``, where ``qhat_s`` is the unit vector
    from neighbour to vehicle at the desired shape.
    """
    f = formation
    q = f.positions[:, None, :] - f.positions[f.slot_neighbour]  # (n, S, 2)
    qhat = q / np.maximum(np.linalg.norm(q, axis=2, keepdims=True), 1e-12)
    qhat = qhat * f.slot_mask[..., None]
    P = np.zeros((f.n, f.slot_mask.shape[1], 2))
    for i in range(f.n):
        Q = qhat[i].T  # (2, S)
        gram = Q @ Q.T
        if np.linalg.cond(gram) < 1e12:
            P[i] = Q.T @ np.linalg.inv(gram)
        else:  # one edge direction (a pair): least squares along it
            P[i] = np.linalg.pinv(Q, rcond=1e-9)
    return P


def _slots_to_edges(formation: Formation, alpha: np.ndarray) -> np.ndarray:
    """Slot coefficients on ``p_i - p_j`` (n, S) -> disagreement matrix on ``z_k`` (n, m)."""
    f = formation
    A = np.zeros((f.n, f.m))
    rows = np.repeat(np.arange(f.n), f.slot_mask.shape[1]).reshape(f.slot_mask.shape)
    A[rows[f.slot_mask], f.slot_edge[f.slot_mask]] = (alpha * f.slot_sign)[f.slot_mask]
    return A


def edges_to_slots(formation: Formation, A: np.ndarray) -> np.ndarray:
    """Disagreement matrix (n, m) -> per-vehicle slot coefficients (n, S).

    Only the vehicle's own edges are read; use :func:`localize` first for matrices
    with entries on other edges (such as ``A_a``).
    """
    f = formation
    rows = np.arange(f.n)[:, None]
    return A[rows, f.slot_edge] * f.slot_sign * f.slot_mask


@dataclass(frozen=True, eq=False)
class MotionBasis:
    """Disagreement matrices (n, m) of the team's rigid motions at scale 1.

    ``translate_x`` and ``translate_y`` are per 1 m/s along the team's body axes;
    ``rotate`` is per 1 rad/s about the centroid (positive: clockwise seen from
    above, i.e. about NED down). ``rotate_mu_max`` is the largest |mu| of ``rotate``.
    """

    formation: Formation
    translate_x: np.ndarray
    translate_y: np.ndarray
    rotate: np.ndarray
    pinv: np.ndarray
    unavailable: tuple[str, ...] = ()
    """Motions the team cannot make (their matrices are zero): ``translate_x``,
    ``translate_y``, ``rotate``; empty for three vehicles or more."""

    @functools.cached_property
    def rotate_mu_max(self) -> float:
        """Largest rotation disagreement per rad/s at scale 1, m/s per rad/s (0: no spin)."""
        return float(np.abs(self.rotate).max())

    @functools.cached_property
    def zhat(self) -> np.ndarray:
        """Unit vectors (m, 2) of the desired shape's edges, team body frame."""
        z = self.formation.relative(self.formation.positions)
        return z / np.linalg.norm(z, axis=1, keepdims=True)

    def angular_rate(self, mu_rotation: float, scale: float) -> float:
        """Angular rate (rad/s) produced when the largest rotation disagreement is ``mu``
        (0 for a team that cannot spin)."""
        if self.rotate_mu_max == 0.0:
            return 0.0
        return mu_rotation / (self.rotate_mu_max * scale)

    def velocity_matrix(self, vx: float, vy: float, omega: float, scale: float) -> np.ndarray:
        """A_v (n, m) for body velocity (vx, vy) m/s and angular rate omega rad/s."""
        return vx * self.translate_x + vy * self.translate_y + omega * scale * self.rotate

    def desired_velocities(self, A_v: np.ndarray) -> np.ndarray:
        """v*_i = sum_k A_v[i, k] zhat*_k in the team body frame, (n, 2)."""
        return A_v @ self.zhat

    def guidance_coefficients(self, A_v: np.ndarray, c1: float,
                              scale: float) -> tuple[np.ndarray, np.ndarray]:
        """Slot coefficients (n, S) of ``c1 A_v`` and of ``A_a`` (eq. udi's ``A`` is their
        sum), each local to its vehicle."""
        f = self.formation
        # Proposition 1's A_a zhat, evaluated right to left: O(n m), not O(n m^2)
        v_star = A_v @ self.zhat
        a_star = A_v @ ((f.incidence.T @ v_star) / (scale * f.distances)[:, None])  # (n, 2)
        alpha_a = np.einsum("isk,ik->is", self.pinv, a_star)
        return c1 * edges_to_slots(f, A_v), alpha_a * f.slot_mask


def centripetal_matrix(A_v: np.ndarray, B: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Proposition 1: A_a = A_v D_(1/d) B^T A_v (n, m), the rigid motion's acceleration."""
    return A_v @ ((B.T / d[:, None]) @ A_v)


def motion_basis(formation: Formation) -> MotionBasis:
    """Synthesise the translation and rotation disagreements of a rigid team."""
    f = formation
    P = local_pseudoinverse(f)
    ones = np.ones(f.n)
    fields = {
        "translate_x": np.column_stack((ones, 0 * ones)),
        "translate_y": np.column_stack((0 * ones, ones)),
        # omega x r about NED down, in the horizontal plane: (-r_y, r_x)
        "rotate": np.column_stack((-f.positions[:, 1], f.positions[:, 0])),
    }
    z = f.relative(f.positions)
    zhat = z / np.linalg.norm(z, axis=1, keepdims=True)
    mats: dict[str, np.ndarray] = {}
    unavailable: list[str] = []
    for name, v in fields.items():
        A = _slots_to_edges(f, np.einsum("isk,ik->is", P, v))
        scale = max(float(np.abs(v).max()), 1e-12)
        if np.abs(A @ zhat - v).max() > 1e-9 * scale:  # some vehicle cannot make it
            A = np.zeros_like(A)
            unavailable.append(name)
        mats[name] = A
    return MotionBasis(formation=f, pinv=P, unavailable=tuple(unavailable), **mats)
