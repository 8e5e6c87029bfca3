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
    ``_params``          The parameters of a simulated vehicle: its autopilot's real tunables,
                         under PX4's names.
    ``_px4_modes``       The PX4 face of one vehicle's modes: the mode its HEARTBEAT reports,
                         and what a PX4 mode request does.
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

from gcs.common import lazy_modules
from vehicles._airframe import BEBOP2, Airframe, check_airframe, load_airframe
from vehicles._autopilot import Autopilot
from vehicles._config import AutopilotConfig, load_autopilot_config
from vehicles._kernel import autopilot_step
from vehicles._outcomes import Denial, RequestOutcome
from vehicles._quaternion import quat_integrate, quat_to_rotation
from vehicles._rotors import rotor_layout
from vehicles._state import AutopilotParams, AutopilotState, Measurements, make_measurements

__all__ = [
    "BEBOP2",
    "Airframe",
    "Autopilot",
    "AutopilotConfig",
    "AutopilotParams",
    "AutopilotState",
    "Denial",
    "Measurements",
    "RequestOutcome",
    "autopilot_step",
    "check_airframe",
    "endpoint",
    "load_airframe",
    "load_autopilot_config",
    "make_measurements",
    "quat_integrate",
    "quat_to_rotation",
    "rotor_layout",
]

__getattr__ = lazy_modules(__name__, ("endpoint",))
