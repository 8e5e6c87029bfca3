"""Simulated sensors: IMU (accelerometer, gyro) and motion-capture pose.

Samples are the true signals plus white noise; the noise comes as standard
normal draws made by :class:`sim.World` from its seeded generator, so the
kernel itself has no random state. The accelerometer measures specific force,
so it feels the rope pull and reads about -g on z_body at rest.
"""

from __future__ import annotations

import numpy as np

from gcs.common import kernel
from sim._state import PhysicsParams, PhysicsState
from vehicles import Measurements, quat_integrate

__all__ = ["sample_imu", "sample_pose"]


@kernel()
def sample_imu(s: PhysicsState, prm: PhysicsParams, meas: Measurements,
               noise: np.ndarray) -> None:
    """New accelerometer and gyro samples for all vehicles; ``noise`` is (N, 6)."""
    for i in range(s.p_ned.shape[0]):
        for k in range(3):
            meas.accel_body[i, k] = s.specific_force_body[i, k] + prm.accel_noise_std * noise[i, k]
            meas.gyro_body[i, k] = s.omega_body[i, k] + prm.gyro_noise_std * noise[i, 3 + k]


@kernel()
def sample_pose(s: PhysicsState, prm: PhysicsParams, meas: Measurements,
                noise: np.ndarray) -> None:
    """New position, velocity and attitude samples for all vehicles; ``noise`` is (N, 9)."""
    for i in range(s.p_ned.shape[0]):
        for k in range(3):
            meas.p_ned[i, k] = s.p_ned[i, k] + prm.position_noise_std * noise[i, k]
            meas.v_ned[i, k] = s.v_ned[i, k] + prm.velocity_noise_std * noise[i, 3 + k]
        sigma = prm.attitude_noise_std
        meas.q_wxyz[i, 0], meas.q_wxyz[i, 1], meas.q_wxyz[i, 2], meas.q_wxyz[i, 3] = \
            quat_integrate(s.q_wxyz[i, 0], s.q_wxyz[i, 1], s.q_wxyz[i, 2], s.q_wxyz[i, 3],
                           sigma * noise[i, 6], sigma * noise[i, 7], sigma * noise[i, 8], 1.0)
        meas.pose_seq[i] += 1
