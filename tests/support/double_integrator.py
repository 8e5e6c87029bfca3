"""Closed loop of eq. dyn: planar double integrators under guidance with a zero-order hold.

The hold is integrated exactly (constant acceleration between ticks), so the
only approximation is the one the real system has: the guidance samples at its
rate and the vehicles hold its output. Also the rotation between NED and a
vehicle's own frame, which the tests of the guidance's frames share.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gcs.guidance import Guidance, MotionDemand


def yaw_rotations(yaw: np.ndarray) -> np.ndarray:
    """R(yaw) (n, 2, 2): own frame to NED for each vehicle (its transpose: NED to own).

    Written out here, not taken from gcs, so that a test holds the kernels to it.
    """
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack((np.stack((c, -s), -1), np.stack((s, c), -1)), -2)


@dataclass
class Trace:
    """Positions, velocities and commands at every tick."""

    t: np.ndarray  # (K,)
    p: np.ndarray  # (K, n, 2)
    v: np.ndarray  # (K, n, 2)
    u: np.ndarray  # (K, n, 2)


def fly(guidance: Guidance, p0: np.ndarray, v0: np.ndarray, demand: MotionDemand,
        duration: float, yaw: np.ndarray | None = None) -> Trace:
    """Run the closed loop for ``duration`` seconds at the guidance rate."""
    T = guidance.period
    steps = round(duration / T)
    yaw = np.zeros(len(p0)) if yaw is None else yaw
    p, v = p0.astype(float).copy(), v0.astype(float).copy()
    P, V, U = [], [], []
    for _ in range(steps):
        u = guidance.accelerations(p, v, yaw, demand)
        P.append(p.copy())
        V.append(v.copy())
        U.append(u)
        p = p + v * T + 0.5 * u * T * T
        v = v + u * T
    return Trace(t=np.arange(steps) * T, p=np.array(P), v=np.array(V), u=np.array(U))
