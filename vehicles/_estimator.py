"""Onboard state estimate: gyro-propagated attitude corrected by pose measurements.

The attitude INDI runs at 512 Hz but motion capture arrives slower, so the
attitude is propagated with the gyro every step and pulled a fixed fraction
towards each new pose sample (a complementary filter, the "KF attitude" block
of the paper's figure 2). Position and velocity are the latest pose sample, the
position taken relative to the vehicle's local origin (its EKF origin).
"""

from __future__ import annotations

import math

from gcs.common import kernel
from vehicles._quaternion import quat_integrate
from vehicles._state import AutopilotParams, AutopilotState, Measurements

__all__ = ["estimate_step"]


@kernel()
def estimate_step(s: AutopilotState, prm: AutopilotParams, meas: Measurements) -> None:
    """Advance every vehicle's estimate by one control step."""
    for i in range(s.q_est.shape[0]):
        qw, qx, qy, qz = quat_integrate(s.q_est[i, 0], s.q_est[i, 1], s.q_est[i, 2],
                                        s.q_est[i, 3], meas.gyro_body[i, 0],
                                        meas.gyro_body[i, 1], meas.gyro_body[i, 2], prm.dt)
        if meas.pose_seq[i] != s.pose_seq_seen[i]:
            k = 1.0 if s.pose_seq_seen[i] == 0 else prm.attitude_correction_gain[i]
            qw, qx, qy, qz = _nlerp(qw, qx, qy, qz, meas.q_wxyz[i, 0], meas.q_wxyz[i, 1],
                                    meas.q_wxyz[i, 2], meas.q_wxyz[i, 3], k)
            for k3 in range(3):
                s.p_est[i, k3] = meas.p_ned[i, k3] - s.origin_ned[i, k3]
                s.v_est[i, k3] = meas.v_ned[i, k3]
            s.pose_seq_seen[i] = meas.pose_seq[i]
        s.q_est[i, 0] = qw
        s.q_est[i, 1] = qx
        s.q_est[i, 2] = qy
        s.q_est[i, 3] = qz


@kernel()
def _nlerp(aw: float, ax: float, ay: float, az: float, bw: float, bx: float, by: float,
           bz: float, k: float) -> tuple[float, float, float, float]:
    """Move unit quaternion a the fraction k towards b along the shorter arc, renormalised."""
    if aw * bw + ax * bx + ay * by + az * bz < 0.0:
        bw, bx, by, bz = -bw, -bx, -by, -bz
    qw = aw + k * (bw - aw)
    qx = ax + k * (bx - ax)
    qy = ay + k * (by - ay)
    qz = az + k * (bz - az)
    norm = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    return qw / norm, qx / norm, qy / norm, qz / norm
