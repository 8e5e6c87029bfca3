"""Rotor layout of an X quadrotor and its control effectiveness.

One definition of where the rotors are and which way they spin, used by the
physics (to turn rotor thrusts into a body wrench) and by the attitude INDI (to
invert that map). Rotor order: front-left, front-right, back-right,
back-left. Spin +1 means the rotor turns about +z_body (clockwise seen from
above); its drag torque on the body is ``-spin * torque_ratio * thrust``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from vehicles._airframe import Airframe

__all__ = ["RotorLayout", "effectiveness_matrix", "rotor_layout"]


class RotorLayout(NamedTuple):
    """Rotor positions and spin directions in the body FRD frame."""

    xy_body: np.ndarray
    """(4, 2) rotor positions (x forward, y right) relative to the centre of mass, m."""
    spin: np.ndarray
    """(4,) +1 or -1, sense of rotation about +z_body."""


def rotor_layout(airframe: Airframe) -> RotorLayout:
    """Rotor positions and spins of an X quadrotor with the airframe's arm offsets."""
    ax, ay = airframe.arm_x, airframe.arm_y
    xy = np.array([[ax, -ay], [ax, ay], [-ax, ay], [-ax, -ay]], dtype=np.float64)
    spin = np.array([1.0, -1.0, 1.0, -1.0])
    return RotorLayout(xy, spin)


def effectiveness_matrix(airframe: Airframe) -> np.ndarray:
    """(4, 4) map from rotor thrusts (N) to [roll, pitch, yaw torque (N m), total thrust (N)].

    Thrust acts along -z_body at each rotor, so rotor j adds ``-y_j T_j`` to the
    roll torque and ``x_j T_j`` to the pitch torque.
    """
    layout = rotor_layout(airframe)
    return np.vstack([
        -layout.xy_body[:, 1],
        layout.xy_body[:, 0],
        -layout.spin * airframe.torque_ratio,
        np.ones(4),
    ])
