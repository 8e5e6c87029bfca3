"""One 512 Hz step of every vehicle's autopilot: estimate, filter, modes, INDI.

The step is a chain of stages, each a loop over all vehicles:

1. attitude/position estimate (:mod:`vehicles._estimator`);
2. Butterworth filters: measured NED acceleration, roll, pitch and modelled
   thrust share one cutoff (acceleration INDI); gyro and modelled rotor thrusts
   share another (attitude INDI). Disarmed vehicles keep their filters at
   steady state on the current signals so arming starts without a transient;
3. mode timers: setpoint timeout, hold timeout, end of climb, touchdown;
4. the acceleration reference nu_a of each vehicle's mode;
5. acceleration INDI, eq. (inca), with the bank limit and the bounded error;
6. attitude INDI down to rotor speed commands, then the actuator model.

A vehicle whose hold point (HOLD) or position (LAND) is on the ground idles
its rotors instead of flying; below the ground clearance TAKEOFF and OFFBOARD
keep the attitude level so INDI cannot tilt a vehicle that friction holds.

Stages take the state NamedTuples and loop inside; the per-vehicle helpers take
plain floats. (Handing NamedTuples of arrays to per-vehicle helpers has a cost
per call in numba; this layout keeps a step of many vehicles cheap: figures in
docs/performance.md, "Why it is fast".)
"""

from __future__ import annotations

import math

from gcs.common import kernel
from gcs.wire import SetpointKind, SimMode
from vehicles._butterworth import biquad_reset, biquad_step
from vehicles._estimator import estimate_step
from vehicles._indi import acceleration_increment, rotor_thrust_increment
from vehicles._quaternion import euler_to_quat, quat_multiply, quat_to_euler, quat_to_rotation
from vehicles._references import altitude_pd, climb_ramp, position_hold
from vehicles._state import AutopilotParams, AutopilotState, Measurements
from vehicles._transitions import enter_disarmed, enter_hold, enter_land

__all__ = ["autopilot_step"]

_DISARMED = int(SimMode.DISARMED)
_TAKEOFF = int(SimMode.TAKEOFF)
_OFFBOARD = int(SimMode.OFFBOARD)
_HOLD = int(SimMode.HOLD)
_LAND = int(SimMode.LAND)
_ACCEL = int(SetpointKind.ACCEL)

_FLY = 0
_IDLE = 1
_OFF = 2


@kernel()
def autopilot_step(s: AutopilotState, prm: AutopilotParams, meas: Measurements) -> None:
    """Advance all autopilots by one control period; writes ``s.rotor_speed_cmd``."""
    s.t[0] += prm.dt
    estimate_step(s, prm, meas)
    _filter_step(s, prm, meas)
    _mode_timers(s, prm)
    _references(s, prm)
    _acceleration_indi(s, prm)
    _attitude_indi(s, prm, meas)


@kernel()
def _activity(mode: int, z_home: float, z_hold: float, z: float, clearance: float) -> int:
    """Whether a vehicle flies, idles on the ground or has its rotors off."""
    if mode == _DISARMED:
        return _OFF
    if mode == _HOLD and z_home - z_hold < clearance:
        return _IDLE
    if mode == _LAND and z_home - z < clearance:
        return _IDLE
    return _FLY


@kernel()
def _filter_step(s: AutopilotState, prm: AutopilotParams, meas: Measurements) -> None:
    kf = prm.thrust_coefficient
    for i in range(s.mode.shape[0]):
        qw, qx, qy, qz = s.q_est[i, 0], s.q_est[i, 1], s.q_est[i, 2], s.q_est[i, 3]
        roll, pitch, _ = quat_to_euler(qw, qx, qy, qz)
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = quat_to_rotation(qw, qx, qy, qz)
        fx, fy, fz = meas.accel_body[i, 0], meas.accel_body[i, 1], meas.accel_body[i, 2]
        t0 = kf * s.rotor_speed_model[i, 0] ** 2
        t1 = kf * s.rotor_speed_model[i, 1] ** 2
        t2 = kf * s.rotor_speed_model[i, 2] ** 2
        t3 = kf * s.rotor_speed_model[i, 3] ** 2
        accel_in = (r00 * fx + r01 * fy + r02 * fz,
                    r10 * fx + r11 * fy + r12 * fz,
                    r20 * fx + r21 * fy + r22 * fz + prm.gravity,
                    roll, pitch, t0 + t1 + t2 + t3)
        rate_in = (meas.gyro_body[i, 0], meas.gyro_body[i, 1], meas.gyro_body[i, 2],
                   t0, t1, t2, t3)
        if s.mode[i] == _DISARMED:
            for j in range(6):
                biquad_reset(prm.accel_coef, s.accel_filter, i, j, accel_in[j])
                s.accel_filtered[i, j] = accel_in[j]
            for j in range(7):
                biquad_reset(prm.rate_coef, s.rate_filter, i, j, rate_in[j])
                s.rate_filtered[i, j] = rate_in[j]
            for k in range(3):
                s.rate_filtered_prev[i, k] = rate_in[k]
            continue
        for j in range(6):
            s.accel_filtered[i, j] = biquad_step(prm.accel_coef, s.accel_filter, i, j,
                                                 accel_in[j])
        for k in range(3):
            s.rate_filtered_prev[i, k] = s.rate_filtered[i, k]
        for j in range(7):
            s.rate_filtered[i, j] = biquad_step(prm.rate_coef, s.rate_filter, i, j, rate_in[j])


@kernel()
def _mode_timers(s: AutopilotState, prm: AutopilotParams) -> None:
    t = s.t[0]
    for i in range(s.mode.shape[0]):
        mode = s.mode[i]
        if mode == _OFFBOARD and t - s.sp_time[i] > prm.setpoint_timeout[i]:
            enter_hold(s, i)
        elif mode == _HOLD and t - s.hold_start[i] > prm.hold_timeout[i]:
            enter_land(s, i)
        elif mode == _TAKEOFF:
            s.z_ref[i] = climb_ramp(s.z_ref[i], s.z_target[i], prm.climb_rate[i], prm.dt)
            if (s.z_ref[i] == s.z_target[i]
                    and abs(s.p_est[i, 2] - s.z_target[i]) < prm.takeoff_tolerance[i]):
                s.mode[i] = _HOLD  # keep holding the takeoff point, now at the target altitude
                s.hold_start[i] = t
                s.p_hold[i, 2] = s.z_target[i]
        elif mode == _LAND:
            if s.z_home[i] - s.p_est[i, 2] < prm.ground_clearance[i]:
                s.touchdown_timer[i] += prm.dt
                if s.touchdown_timer[i] >= prm.touchdown_time[i]:
                    enter_disarmed(s, i)
            else:
                s.touchdown_timer[i] = 0.0


@kernel()
def _references(s: AutopilotState, prm: AutopilotParams) -> None:
    """Acceleration reference nu_a (NED, m/s^2) of each flying vehicle's mode."""
    for i in range(s.mode.shape[0]):
        mode = s.mode[i]
        pz, vz = s.p_est[i, 2], s.v_est[i, 2]
        if _activity(mode, s.z_home[i], s.p_hold[i, 2], pz,
                     prm.ground_clearance[i]) != _FLY:
            nu_x = nu_y = nu_z = 0.0
        elif mode == _OFFBOARD:
            nu_x, nu_y = s.sp_accel_ned[i, 0], s.sp_accel_ned[i, 1]
            if s.sp_kind[i] == _ACCEL:
                nu_z = s.sp_accel_ned[i, 2]
            else:
                nu_z = altitude_pd(pz, vz, s.sp_z_ned[i], 0.0, prm.altitude_kp[i],
                                   prm.altitude_kv[i])
        else:
            nu_x, nu_y = position_hold(s.p_est[i, 0], s.p_est[i, 1], s.v_est[i, 0],
                                       s.v_est[i, 1], s.p_hold[i, 0], s.p_hold[i, 1],
                                       prm.hold_kp[i], prm.hold_kv[i])
            if mode == _TAKEOFF:
                vz_ref = 0.0
                if s.z_ref[i] != s.z_target[i]:
                    vz_ref = (-prm.climb_rate[i] if s.z_target[i] < s.z_ref[i]
                              else prm.climb_rate[i])
                nu_z = altitude_pd(pz, vz, s.z_ref[i], vz_ref, prm.altitude_kp[i],
                                   prm.altitude_kv[i])
            elif mode == _LAND:
                nu_z = prm.altitude_kv[i] * (prm.land_speed[i] - vz)
            else:
                nu_z = altitude_pd(pz, vz, s.p_hold[i, 2], 0.0, prm.altitude_kp[i],
                                   prm.altitude_kv[i])
        s.accel_ref_ned[i, 0] = nu_x
        s.accel_ref_ned[i, 1] = nu_y
        s.accel_ref_ned[i, 2] = nu_z


@kernel()
def _acceleration_indi(s: AutopilotState, prm: AutopilotParams) -> None:
    """Eq. (inca) on the filtered signals: commanded roll, pitch, yaw and total thrust."""
    rotor_max = prm.thrust_coefficient * prm.rotor_speed_max**2
    for i in range(s.mode.shape[0]):
        rotor_idle = prm.thrust_coefficient * prm.rotor_speed_idle[i]**2
        bank = prm.bank_max[i]
        if s.mode[i] == _OFFBOARD and not math.isnan(s.sp_yaw[i]):
            s.yaw_hold[i] = s.sp_yaw[i]
        s.attitude_cmd[i, 2] = s.yaw_hold[i]
        activity = _activity(s.mode[i], s.z_home[i], s.p_hold[i, 2], s.p_est[i, 2],
                             prm.ground_clearance[i])
        if activity != _FLY:
            s.attitude_cmd[i, 0] = 0.0
            s.attitude_cmd[i, 1] = 0.0
            s.thrust_cmd[i] = 4.0 * rotor_idle if activity == _IDLE else 0.0
            continue
        yaw = quat_to_euler(s.q_est[i, 0], s.q_est[i, 1], s.q_est[i, 2], s.q_est[i, 3])[2]
        roll_f, pitch_f = s.accel_filtered[i, 3], s.accel_filtered[i, 4]
        thrust_f = s.accel_filtered[i, 5]
        lim = prm.accel_error_max_xy[i]
        ex = min(lim, max(-lim, s.accel_ref_ned[i, 0] - s.accel_filtered[i, 0]))
        ey = min(lim, max(-lim, s.accel_ref_ned[i, 1] - s.accel_filtered[i, 1]))
        ez = min(prm.accel_error_max_z[i],
                 max(-prm.accel_error_max_z[i], s.accel_ref_ned[i, 2] - s.accel_filtered[i, 2]))
        level = s.z_home[i] - s.p_est[i, 2] < prm.ground_clearance[i]
        if level:
            ex = 0.0
            ey = 0.0
        d_roll, d_pitch, d_thrust_z = acceleration_increment(
            roll_f, pitch_f, yaw, -max(thrust_f, prm.thrust_floor[i]), prm.mass, ex, ey, ez)
        s.attitude_cmd[i, 0] = 0.0 if level else min(bank, max(-bank, roll_f + d_roll))
        s.attitude_cmd[i, 1] = 0.0 if level else min(bank, max(-bank, pitch_f + d_pitch))
        s.thrust_cmd[i] = min(4.0 * rotor_max, max(4.0 * rotor_idle, thrust_f - d_thrust_z))


@kernel()
def _attitude_indi(s: AutopilotState, prm: AutopilotParams, meas: Measurements) -> None:
    """Rotor speed commands from the attitude and thrust commands, then the actuator model."""
    kf = prm.thrust_coefficient
    rotor_max = kf * prm.rotor_speed_max**2
    for i in range(s.mode.shape[0]):
        rotor_idle = kf * prm.rotor_speed_idle[i]**2
        activity = _activity(s.mode[i], s.z_home[i], s.p_hold[i, 2], s.p_est[i, 2],
                             prm.ground_clearance[i])
        if activity == _OFF:
            for j in range(4):
                s.rotor_speed_cmd[i, j] = 0.0
                s.rotor_speed_model[i, j] = 0.0
            continue
        if activity == _IDLE:
            for j in range(4):
                s.rotor_speed_cmd[i, j] = prm.rotor_speed_idle[i]
        else:
            qw, qx, qy, qz = s.q_est[i, 0], s.q_est[i, 1], s.q_est[i, 2], s.q_est[i, 3]
            cw, cx, cy, cz = euler_to_quat(s.attitude_cmd[i, 0], s.attitude_cmd[i, 1],
                                           s.attitude_cmd[i, 2])
            ew, ex, ey, ez = quat_multiply(qw, -qx, -qy, -qz, cw, cx, cy, cz)
            if ew < 0.0:
                ex, ey, ez = -ex, -ey, -ez
            # Angular acceleration reference minus the derivative of the filtered gyro.
            ka, kr = prm.attitude_gain, prm.rate_gain
            d_alpha_x = (ka[i, 0] * 2.0 * ex - kr[i, 0] * meas.gyro_body[i, 0]
                         - (s.rate_filtered[i, 0] - s.rate_filtered_prev[i, 0]) / prm.dt)
            d_alpha_y = (ka[i, 1] * 2.0 * ey - kr[i, 1] * meas.gyro_body[i, 1]
                         - (s.rate_filtered[i, 1] - s.rate_filtered_prev[i, 1]) / prm.dt)
            d_alpha_z = (ka[i, 2] * 2.0 * ez - kr[i, 2] * meas.gyro_body[i, 2]
                         - (s.rate_filtered[i, 2] - s.rate_filtered_prev[i, 2]) / prm.dt)
            thrust_inner_f = (s.rate_filtered[i, 3] + s.rate_filtered[i, 4]
                              + s.rate_filtered[i, 5] + s.rate_filtered[i, 6])
            d_rotor = rotor_thrust_increment(prm.effectiveness_inv, prm.inertia, d_alpha_x,
                                             d_alpha_y, d_alpha_z, s.thrust_cmd[i] - thrust_inner_f)
            for j in range(4):
                rotor_thrust = min(rotor_max,
                                   max(rotor_idle, s.rate_filtered[i, 3 + j] + d_rotor[j]))
                s.rotor_speed_cmd[i, j] = math.sqrt(rotor_thrust / kf)
        for j in range(4):
            s.rotor_speed_model[i, j] += prm.actuator_alpha * (
                s.rotor_speed_cmd[i, j] - s.rotor_speed_model[i, j])
