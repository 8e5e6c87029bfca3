"""The stepping loops: many physics steps, with or without the autopilots.

Python calls :func:`run_physics` (fixed rotor commands) or :func:`run_lockstep`
(autopilot and physics in turn) once per chunk of many steps, so the per-step
cost is compiled code only. Sensors sample when the physics step counter is a
multiple of their period; noise arrays hold exactly one row per sample in the
chunk (:func:`samples_in`), which keeps runs identical however they are chunked.
"""

from __future__ import annotations

import numpy as np

from gcs.common import kernel
from sim._dynamics import physics_step
from sim._sensors import sample_imu, sample_pose
from sim._state import PhysicsParams, PhysicsState
from vehicles import AutopilotParams, AutopilotState, Measurements, autopilot_step

__all__ = ["run_lockstep", "run_physics", "samples_in"]


def samples_in(first_step: int, n_steps: int, every: int) -> int:
    """How many multiples of ``every`` lie in (first_step, first_step + n_steps]."""
    return (first_step + n_steps) // every - first_step // every


@kernel(nogil=True)
def run_physics(s: PhysicsState, prm: PhysicsParams, meas: Measurements, cmd: np.ndarray,
                n_steps: int, gust_noise: np.ndarray, imu_noise: np.ndarray,
                pose_noise: np.ndarray) -> None:
    """``n_steps`` physics steps holding the rotor commands ``cmd`` (N, 4)."""
    imu_base = s.step[0] // prm.imu_every + 1
    pose_base = s.step[0] // prm.pose_every + 1
    for n in range(n_steps):
        physics_step(s, prm, cmd, gust_noise[n])
        k = s.step[0]
        if k % prm.imu_every == 0:
            sample_imu(s, prm, meas, imu_noise[k // prm.imu_every - imu_base])
        if k % prm.pose_every == 0:
            sample_pose(s, prm, meas, pose_noise[k // prm.pose_every - pose_base])


@kernel(nogil=True)
def run_lockstep(s: PhysicsState, prm: PhysicsParams, meas: Measurements, aps: AutopilotState,
                 app: AutopilotParams, n_control: int, substeps: int, gust_noise: np.ndarray,
                 imu_noise: np.ndarray, pose_noise: np.ndarray) -> None:
    """``n_control`` autopilot steps, each followed by ``substeps`` physics steps."""
    imu_base = s.step[0] // prm.imu_every + 1
    pose_base = s.step[0] // prm.pose_every + 1
    n = 0
    for _ in range(n_control):
        autopilot_step(aps, app, meas)
        for _ in range(substeps):
            physics_step(s, prm, aps.rotor_speed_cmd, gust_noise[n])
            n += 1
            k = s.step[0]
            if k % prm.imu_every == 0:
                sample_imu(s, prm, meas, imu_noise[k // prm.imu_every - imu_base])
            if k % prm.pose_every == 0:
                sample_pose(s, prm, meas, pose_noise[k // prm.pose_every - pose_base])
