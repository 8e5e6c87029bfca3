"""Onboard autopilot of a simulated rotorcraft: INDI control, modes, MAVLink endpoint.

Modules:

    ``_airframe``        Airframe parameters of one rotorcraft, loaded from
                         configs/airframes/*.yaml.
    ``_autopilot``       The onboard autopilots of a team: commands, setpoints, one control
                         step, telemetry.
    ``_battery``         Battery of a simulated vehicle: charge drawn by the rotors, voltage
                         sag, remaining charge.
    ``_butterworth``     Second-order Butterworth low-pass filters for the INDI loops.
    ``_commands``        COMMAND_LONG of a simulated vehicle: what each command does and its
                         COMMAND_ACK result.
    ``_config``          Autopilot configuration: loop rate, filter cutoffs, gains, limits
                         and timeouts.
    ``_estimator``       Onboard state estimate: gyro-propagated attitude corrected by pose
                         measurements.
    ``_indi``            Incremental nonlinear dynamic inversion (INDI) laws of the paper's
                         section IV.
    ``_kernel``          One 512 Hz step of every vehicle's autopilot: estimate, filter,
                         modes, INDI.
    ``_outcomes``        Outcomes of a request to the onboard autopilot: accepted, or denied
                         and why.
    ``_quaternion``      Quaternion and Euler-angle helpers shared by the autopilot and the
                         physics.
    ``_references``      Acceleration references nu_a of the autopilot's own modes.
    ``_reports``         Telemetry messages of one simulated vehicle, built from its
                         autopilot's own state.
    ``_rotors``          Rotor layout of an X quadrotor and its control effectiveness.
    ``_setpoint_check``  Input checks on SET_POSITION_TARGET_LOCAL_NED before a setpoint may
                         reach the autopilot.
    ``_state``           Arrays the autopilot kernel reads and writes, batched over
                         vehicles.
    ``_streams``         Which telemetry messages a vehicle streams, how often, and when
                         each is next due.
    ``_transitions``     Mode entry actions, shared by the kernel (timeouts, touchdown) and
                         by commands.
    ``endpoint``         The MAVLink 2 endpoint of one simulated vehicle: its system id,
                         commands, setpoints, telemetry.
"""

from vehicles import endpoint
from vehicles._airframe import BEBOP2, Airframe, bebop2, load_airframe
from vehicles._autopilot import Autopilot
from vehicles._battery import AIR_DENSITY, Battery, BatteryConfig, BatteryReading
from vehicles._butterworth import biquad_reset, biquad_step, butterworth2
from vehicles._commands import FORCE_DISARM_MAGIC, CommandOutcome, MavResult, execute_command
from vehicles._config import AutopilotConfig, load_autopilot_config
from vehicles._estimator import estimate_step
from vehicles._indi import acceleration_increment, g_matrix, rotor_thrust_increment
from vehicles._kernel import autopilot_step
from vehicles._outcomes import Denial, RequestOutcome
from vehicles._quaternion import (
    euler_from_quaternions,
    euler_to_quat,
    quat_integrate,
    quat_multiply,
    quat_to_euler,
    quat_to_rotation,
)
from vehicles._references import altitude_pd, climb_ramp, position_hold
from vehicles._reports import LOW_BATTERY, CommCounters, VehicleView, build_report, time_boot_ms
from vehicles._rotors import RotorLayout, effectiveness_matrix, rotor_layout
from vehicles._setpoint_check import Refusal, SetpointLimits, SetpointVerdict, check_setpoint
from vehicles._state import (
    ACCEL_SIGNALS,
    GRAVITY,
    RATE_SIGNALS,
    AutopilotParams,
    AutopilotState,
    Measurements,
    make_autopilot_params,
    make_autopilot_state,
    make_measurements,
)
from vehicles._streams import DEFAULT_RATES_HZ, IntervalRequest, StreamSchedule, TelemetryMessage
from vehicles._transitions import (
    enter_armed_hold,
    enter_disarmed,
    enter_hold,
    enter_land,
    enter_offboard,
    enter_takeoff,
)

__all__ = [
    "ACCEL_SIGNALS",
    "AIR_DENSITY",
    "BEBOP2",
    "DEFAULT_RATES_HZ",
    "FORCE_DISARM_MAGIC",
    "GRAVITY",
    "LOW_BATTERY",
    "RATE_SIGNALS",
    "Airframe",
    "Autopilot",
    "AutopilotConfig",
    "AutopilotParams",
    "AutopilotState",
    "Battery",
    "BatteryConfig",
    "BatteryReading",
    "CommCounters",
    "CommandOutcome",
    "Denial",
    "IntervalRequest",
    "MavResult",
    "Measurements",
    "Refusal",
    "RequestOutcome",
    "RotorLayout",
    "SetpointLimits",
    "SetpointVerdict",
    "StreamSchedule",
    "TelemetryMessage",
    "VehicleView",
    "acceleration_increment",
    "altitude_pd",
    "autopilot_step",
    "bebop2",
    "biquad_reset",
    "biquad_step",
    "build_report",
    "butterworth2",
    "check_setpoint",
    "climb_ramp",
    "effectiveness_matrix",
    "endpoint",
    "enter_armed_hold",
    "enter_disarmed",
    "enter_hold",
    "enter_land",
    "enter_offboard",
    "enter_takeoff",
    "estimate_step",
    "euler_from_quaternions",
    "euler_to_quat",
    "execute_command",
    "g_matrix",
    "load_airframe",
    "load_autopilot_config",
    "make_autopilot_params",
    "make_autopilot_state",
    "make_measurements",
    "position_hold",
    "quat_integrate",
    "quat_multiply",
    "quat_to_euler",
    "quat_to_rotation",
    "rotor_layout",
    "rotor_thrust_increment",
    "time_boot_ms",
]
