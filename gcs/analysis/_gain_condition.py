"""Eq. max's left side: the guidance's worst demand on one axis, from its gains.

``c1 ||e_v|| + c2 e_max kappa + mu_r ||z||_max`` with kappa the largest sum, over one
vehicle's edges, of their unit vectors' components along a team axis (1 + 0.7 for
the square) and ``||z||_max`` the longest edge carrying rotation disagreement,
stretched by ``e_max``. It must not exceed the per-axis limit the force chain leaves
(:mod:`gcs.analysis._forces`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gcs.config import Team

__all__ = ["GainCondition", "gain_condition", "kappa", "rotation_edge"]


def kappa(positions: np.ndarray, neighbours: np.ndarray, mask: np.ndarray) -> float:
    """Largest sum of |unit edge vector . axis| over one vehicle's edges, team axes
    (``neighbours[i, s]`` the vehicle at slot ``s`` of vehicle ``i``, ``mask`` its use)."""
    q = positions[:, None, :] - positions[neighbours]
    qhat = q / np.maximum(np.linalg.norm(q, axis=2, keepdims=True), 1e-12)
    return float((np.abs(qhat) * mask[..., None]).sum(axis=1).max())


def rotation_edge(distances: np.ndarray, rotate: np.ndarray) -> float:
    """The longest edge that carries rotation disagreement (``rotate``: the motion basis'
    rotation per vehicle and edge), or the longest edge when none does."""
    carrying = np.abs(rotate).max(axis=0) > 1e-9
    return float(distances[carrying].max() if carrying.any() else distances.max())


@dataclass(frozen=True)
class GainCondition:
    """The terms of eq. max's left side and what they are made of (SI units)."""

    c1: float
    c2: float
    mu_r: float
    speed_error: float
    distance_error: float
    kappa: float
    worst_edge: float
    """``||z||_max``: the longest rotating edge, stretched by the distance error."""
    terms: dict[str, float]
    """Each term of the left side, m/s^2, by name (``c1_speed``, ``c2_distance``,
    ``mu_rotation``)."""

    @property
    def lhs(self) -> float:
        """The left side: the sum of the terms, m/s^2."""
        return sum(self.terms.values())

    def per_unit(self) -> dict[str, float]:
        """Each term per unit of its gain."""
        return {"c1_speed": self.speed_error, "c2_distance": self.distance_error * self.kappa,
                "mu_rotation": self.worst_edge}

    def coefficients(self) -> dict[str, float]:
        """The gains and figures of the terms, under the certificate's key names."""
        return {"c1": self.c1, "c2": self.c2, "mu_r": self.mu_r,
                "speed_error_m_s": self.speed_error, "distance_error_m": self.distance_error,
                "kappa": self.kappa, "worst_edge_m": self.worst_edge}

    def c2_room(self, limit: float) -> float:
        """The distance gain eq. max leaves room for under ``limit``, the other terms as
        they are."""
        return (limit - self.lhs + self.terms["c2_distance"]) / (self.distance_error
                                                                 * self.kappa)


def gain_condition(team: Team, rotate: np.ndarray) -> GainCondition:
    """Eq. max's left side for ``team`` (``rotate``: its motion basis' rotation)."""
    cfg = team.config
    f = team.formation
    e_max = cfg.analysis.max_distance_error
    ev_max = cfg.analysis.max_speed_error or cfg.guidance.max_speed
    edge = rotation_edge(f.distances, rotate) + e_max
    k = kappa(f.positions, f.slot_neighbour, f.slot_mask)
    c1, c2, mu_r = cfg.guidance.c1, cfg.guidance.c2, cfg.guidance.max_rotation_disagreement
    terms = {"c1_speed": c1 * ev_max, "c2_distance": c2 * e_max * k, "mu_rotation": mu_r * edge}
    return GainCondition(c1=c1, c2=c2, mu_r=mu_r, speed_error=ev_max, distance_error=e_max,
                         kappa=k, worst_edge=edge, terms=terms)
