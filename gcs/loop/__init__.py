"""The GCS's 4 Hz loop: fleet table, safety rules, operator, phases, runtime.

:class:`Runtime` ticks on a :class:`Clock` (wall or simulator time): the fleet's
latest telemetry, the safety rules, the operator's command, the guidance, one
setpoint per vehicle, the phase actions; it records through a
:class:`FlightRecorder`.

Modules (the tick's stages are ``*_stage``; gcs/loop/README.md maps them):

    ``_actions``        The operator's phase actions, run off the loop: arm, take off,
                        lift, land, resume, abort.
    ``_clock``          Clocks: where every loop takes its time from.
    ``_deformation``    A team deformed beyond the safe bound: hold, re-form, or land.
    ``_demand_stage``   What the operator asks of the team this tick, and what it may fly.
    ``_events``         The operator's event log: phase changes, warnings and errors.
    ``_fleet``          The team's latest state as arrays, read from the links once per tick.
    ``_gamepad``        A gamepad on the GCS side: sticks, altitude, scale, guidance switch,
                        abort and resume.
    ``_geofence``       The geofence: the team slows to a stop at it and can fly back.
    ``_guidance_stage`` One horizontal acceleration per vehicle for this tick.
    ``_load_share``     Load sharing: each vehicle's altitude trimmed so the payload's weight
                        splits as designed.
    ``_load_share_stage``  The altitude trims moved on each tick's thrusts.
    ``_operator``       The operator's command: one object written by any source, read by
                        the 4 Hz loop.
    ``_phase_machine``  The flight phase as state, moved by the loop and the actions alike.
    ``_phase_stage``    The phase transitions each tick makes on its own.
    ``_phases``         Flight phases of a transport and which operator action leads where.
    ``_prearm``         Checks before arming: every refusal names the vehicle and the reason.
    ``_reached``        An altitude reached: each vehicle counted once it has been within
                        tolerance of it.
    ``_record``         What the loop records of a flight: the recorder, each tick's internals.
    ``_recovery``       Recovery after a setpoint gap: when vehicles that dropped to hold fly
                        again.
    ``_rope_lead_stage``  The guidance's accelerations ahead of the ropes' changing pulls.
    ``_runtime``        The GCS loop: the stages wired, and the schedule they tick on.
    ``_safety``         Safety rules of the GCS loop, each enforced here and nowhere else.
    ``_safety_stage``   This tick's safety verdict, and what the team does about it.
    ``_setpoint_stage`` Each vehicle's altitude target, and the stream to the team.
    ``_snapshot``       What one tick leaves for the page and the metrics; the ticks' timing.
    ``_stepgate``       In lockstep with the simulator, helper threads act only at ticks.
    ``_team_frame``     One team frame: every vehicle placed in one NED frame about a team
                        origin.
    ``_vehicle_modes``  Each vehicle's flight mode against the one the GCS's setpoints need.
"""

from gcs.loop._clock import Clock, ClockStoppedError, ExternalClock, WallClock
from gcs.loop._deformation import Deformation
from gcs.loop._demand_stage import LINK_DELAY_CAP_S
from gcs.loop._events import Event
from gcs.loop._fleet import FleetState, FleetTable
from gcs.loop._gamepad import Gamepad, load_gamepad_config
from gcs.loop._geofence import FenceVerdict
from gcs.loop._load_share import LoadSharing, estimated_shares, free_split
from gcs.loop._operator import OperatorCommand, OperatorSnapshot
from gcs.loop._phases import Action, Phase, PhaseError
from gcs.loop._prearm import Prearm, PrearmError
from gcs.loop._record import FlightRecorder
from gcs.loop._runtime import Runtime, Stages
from gcs.loop._safety import SafetyReason
from gcs.loop._setpoint_stage import HELD_SETPOINT_S
from gcs.loop._snapshot import RuntimeSnapshot, TickStats
from gcs.loop._stepgate import HOLD_CAP_S, GatedClock, StepGate
from gcs.loop._team_frame import TeamFrame

__all__ = [
    "HELD_SETPOINT_S",
    "HOLD_CAP_S",
    "LINK_DELAY_CAP_S",
    "Action",
    "Clock",
    "ClockStoppedError",
    "Deformation",
    "Event",
    "ExternalClock",
    "FenceVerdict",
    "FleetState",
    "FleetTable",
    "FlightRecorder",
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
    "Stages",
    "StepGate",
    "TeamFrame",
    "TickStats",
    "WallClock",
    "estimated_shares",
    "free_split",
    "load_gamepad_config",
]
