"""Autopilot configuration: loop rate, filter cutoffs, gains, limits and timeouts.

Loaded from configs/sim/autopilot.yaml. Defaults follow the seed's Paparazzi
settings for the Bebop (512 Hz, 20 degrees bank, ±6 m/s² acceleration error,
0.5 s setpoint timeout) and the paper's section "Rotorcraft control".
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gcs.common import field, from_mapping, load_yaml

__all__ = ["AutopilotConfig", "load_autopilot_config"]


@dataclass(frozen=True)
class AutopilotConfig:
    """Settings shared by every vehicle's onboard autopilot."""

    rate_hz: float = field(doc="control loop rate, Hz", default=512.0, gt=0.0)
    accel_filter_cutoff_hz: float = field(
        doc="Butterworth cutoff shared by measured acceleration, attitude and thrust "
            "in the acceleration INDI, Hz", default=5.0, gt=0.0)
    rate_filter_cutoff_hz: float = field(
        doc="Butterworth cutoff shared by the gyro and the actuator model in the attitude INDI, Hz",
        default=20.0, gt=0.0)
    bank_max_deg: float = field(doc="largest commanded roll and pitch, deg", default=20.0,
                                gt=0.0, lt=90.0)
    accel_error_max_xy: float = field(
        doc="bound on each horizontal acceleration error fed to INDI, m/s^2", default=6.0, gt=0.0)
    accel_error_max_z: float = field(
        doc="bound on the vertical acceleration error fed to INDI, m/s^2", default=6.0, gt=0.0)
    attitude_gain: tuple[float, float, float] = field(
        doc="angular acceleration per attitude error about body x, y, z, 1/s^2",
        default=(300.0, 300.0, 60.0), gt=0.0)
    rate_gain: tuple[float, float, float] = field(
        doc="angular acceleration per body rate about x, y, z, 1/s",
        default=(28.0, 28.0, 14.0), gt=0.0)
    altitude_kp: float = field(doc="eq. (pdalt) altitude gain k_p, 1/s^2", default=4.0, gt=0.0)
    altitude_kv: float = field(doc="eq. (pdalt) vertical speed gain k_v, 1/s", default=3.2,
                               gt=0.0)
    hold_kp: float = field(doc="horizontal position gain of HOLD, TAKEOFF and LAND, 1/s^2",
                           default=1.5, gt=0.0)
    hold_kv: float = field(doc="horizontal speed gain of HOLD, TAKEOFF and LAND, 1/s",
                           default=2.2, gt=0.0)
    climb_rate: float = field(doc="TAKEOFF climb speed, m/s", default=0.5, gt=0.0)
    land_speed: float = field(doc="LAND descent speed, m/s", default=0.4, gt=0.0)
    takeoff_altitude: float = field(
        doc="climb of a take-off that names no altitude (PX4's AUTO.TAKEOFF mode, NAV_TAKEOFF "
            "with param7 NaN), m above the arming point", default=1.5, gt=0.0)
    takeoff_tolerance: float = field(
        doc="TAKEOFF ends in HOLD once within this distance of the target altitude, m",
        default=0.05, gt=0.0)
    setpoint_timeout: float = field(
        doc="OFFBOARD switches to HOLD after this long without a setpoint, s", default=0.5, gt=0.0)
    hold_timeout: float = field(doc="HOLD switches to LAND after this long without a command, s",
                                default=20.0, gt=0.0)
    ground_clearance: float = field(
        doc="height above the arming point below which the vehicle counts as on the ground, m",
        default=0.05, gt=0.0)
    touchdown_time: float = field(doc="time on the ground in LAND before disarming, s",
                                  default=0.5, gt=0.0)
    idle_thrust_fraction: float = field(
        doc="rotor thrust while armed on the ground, fraction of one rotor's maximum",
        default=0.03, ge=0.0, lt=1.0)
    thrust_floor_fraction: float = field(
        doc="smallest thrust used in the G matrix, fraction of the weight (keeps G invertible "
            "on the ground)", default=0.5, gt=0.0)
    attitude_correction_gain: float = field(
        doc="fraction of the attitude difference to each pose measurement taken per sample",
        default=0.05, gt=0.0, le=1.0)


def load_autopilot_config(path: str | Path) -> AutopilotConfig:
    """Load and validate an autopilot configuration file."""
    return from_mapping(AutopilotConfig, load_yaml(path) or {}, str(path))
