"""The GCS's 4 Hz loop: fleet table, safety rules, operator, phases, runtime.

:class:`Runtime` ticks on a :class:`Clock` (wall or simulator time): the fleet's
latest telemetry, the safety rules, the operator's command, the guidance, one
setpoint per vehicle, the phase actions; it records through a
:class:`FlightRecorder`.

Modules:

    ``_clock``     Clocks: where every loop takes its time from.
    ``_deformation``  A team deformed beyond the safe bound: hold, re-form, or land.
    ``_fleet``     The team's latest state as arrays, read from the links once per tick.
    ``_geofence``  The geofence: the team slows to a stop at it and can fly back.
    ``_load_share``  Load sharing: each vehicle's altitude trimmed so the payload's weight
                   splits as designed.
    ``_gamepad``   A gamepad on the GCS side: sticks, altitude, scale, guidance switch,
                   abort and resume.
    ``_operator``  The operator's command: one object written by any source, read by the 4
                   Hz loop.
    ``_phases``    Flight phases of a transport and which operator action leads where.
    ``_prearm``    Checks before arming: every refusal names the vehicle and the reason.
    ``_reached``   An altitude reached: each vehicle counted once it has been within
                   tolerance of it.
    ``_recovery``  Recovery after a setpoint gap: when vehicles that dropped to hold fly
                   again.
    ``_runtime``   The GCS loop: operator sticks in, one acceleration setpoint per vehicle
                   out, at 4 Hz.
    ``_safety``    Safety rules of the GCS loop, each enforced here and nowhere else.
    ``_stepgate``  In lockstep with the simulator, helper threads act only at ticks.
    ``_team_frame``  One team frame: every vehicle placed in one NED frame about a team
                   origin.
"""

from gcs.loop._clock import Clock, ClockStoppedError, ExternalClock, WallClock
from gcs.loop._deformation import Deformation
from gcs.loop._fleet import FleetState, FleetTable
from gcs.loop._gamepad import Gamepad, load_gamepad_config
from gcs.loop._geofence import FenceVerdict
from gcs.loop._load_share import LoadSharing, estimated_shares, free_split
from gcs.loop._operator import OperatorCommand, OperatorSnapshot
from gcs.loop._phases import Action, Phase, PhaseError
from gcs.loop._prearm import Prearm, PrearmError
from gcs.loop._runtime import Runtime, RuntimeSnapshot, TickStats
from gcs.loop._safety import SafetyReason
from gcs.loop._stepgate import HOLD_CAP_S, GatedClock, StepGate
from gcs.loop._team_frame import TeamFrame

__all__ = [
    "HOLD_CAP_S",
    "Action",
    "Clock",
    "ClockStoppedError",
    "Deformation",
    "ExternalClock",
    "FenceVerdict",
    "FleetState",
    "FleetTable",
    "Gamepad",
    "GatedClock",
    "LoadSharing",
    "OperatorCommand",
    "OperatorSnapshot",
    "Phase",
    "PhaseError",
    "Prearm",
    "PrearmError",
    "Runtime",
    "RuntimeSnapshot",
    "SafetyReason",
    "StepGate",
    "TeamFrame",
    "TickStats",
    "WallClock",
    "estimated_shares",
    "free_split",
    "load_gamepad_config",
]
