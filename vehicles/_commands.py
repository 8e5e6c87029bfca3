"""COMMAND_LONG of a simulated vehicle: what each command does and its COMMAND_ACK result.

Why: the GCS's autopilot profile (``gcs.link._profile_sim``) drives the
vehicle with exactly these commands and confirms each step, so every command
must map onto one :class:`~vehicles.Autopilot` action and answer
with the result a real autopilot would give:

=============================  ==========================================================
command                        effect
=============================  ==========================================================
COMPONENT_ARM_DISARM           param1 1 arm, 0 disarm (param2 21196 forces it in flight)
NAV_TAKEOFF                    climb param7 m above the current position, then HOLD
NAV_LAND                       land where the vehicle is, disarm on touchdown
DO_SET_MODE                    param1 with CUSTOM_MODE_ENABLED, param2 a ``SimMode``
SET_MESSAGE_INTERVAL           param1 message id, param2 interval in us (-1 stop, 0 default)
anything else                  UNSUPPORTED
=============================  ==========================================================

Refusals are DENIED, except arming before the first position sample, which
is TEMPORARILY_REJECTED (the GCS retries); each refusal also has a reason for
a STATUSTEXT.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gcs.wire import CUSTOM_MODE_ENABLED, CommandResult, MavMessage, SimMode, mavlink
from vehicles._autopilot import Autopilot
from vehicles._outcomes import Denial, RequestOutcome
from vehicles._streams import IntervalRequest, StreamSchedule

__all__ = ["FORCE_DISARM_MAGIC", "CommandOutcome", "execute_command"]

FORCE_DISARM_MAGIC = 21196
"""COMPONENT_ARM_DISARM param2 that disarms even in flight (the MAVLink convention)."""


@dataclass(frozen=True)
class CommandOutcome:
    """Result for the COMMAND_ACK and, when refused, the reason for a STATUSTEXT."""

    result: CommandResult
    reason: str = ""


_ACCEPTED = CommandOutcome(CommandResult.ACCEPTED)


def execute_command(msg: MavMessage, autopilot: Autopilot, index: int,
                    streams: StreamSchedule, t: float) -> CommandOutcome:
    """Carry out one COMMAND_LONG for vehicle ``index`` at sim time ``t``."""
    command = msg.command
    if command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
        return _arm_disarm(msg, autopilot, index)
    if command == mavlink.MAV_CMD_NAV_TAKEOFF:
        return _takeoff(msg.param7, autopilot, index)
    if command == mavlink.MAV_CMD_NAV_LAND:
        return _outcome(autopilot.land(index), "land")
    if command == mavlink.MAV_CMD_DO_SET_MODE:
        return _set_mode(msg, autopilot, index)
    if command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
        request = streams.set_interval(int(msg.param1) if math.isfinite(msg.param1) else -1,
                                       msg.param2, t)
        if request is IntervalRequest.SET:
            return _ACCEPTED
        return CommandOutcome(CommandResult.DENIED, f"interval: {request.value}")
    return CommandOutcome(CommandResult.UNSUPPORTED)


def _arm_disarm(msg: MavMessage, autopilot: Autopilot, index: int) -> CommandOutcome:
    if msg.param1 == 1.0:
        return _outcome(autopilot.arm(index), "arm")
    if msg.param1 == 0.0:
        return _outcome(autopilot.disarm(index, force=msg.param2 == FORCE_DISARM_MAGIC),
                        "disarm")
    return CommandOutcome(CommandResult.DENIED, f"arm: param1 must be 0 or 1, got {msg.param1:g}")


def _takeoff(climb_m: float, autopilot: Autopilot, index: int) -> CommandOutcome:
    """NAV_TAKEOFF param7 is the climb above the current position (see gcs.link._profile_sim)."""
    if not math.isfinite(climb_m) or climb_m <= 0.0:
        return CommandOutcome(CommandResult.DENIED, "takeoff: param7 must be a climb > 0 m")
    state = autopilot.state
    height = float(state.z_home[index] - state.p_est[index, 2]) if autopilot.armed[index] else 0.0
    return _outcome(autopilot.takeoff(index, max(0.0, height) + climb_m), "takeoff")


def _set_mode(msg: MavMessage, autopilot: Autopilot, index: int) -> CommandOutcome:
    if not math.isfinite(msg.param1) or not int(msg.param1) & CUSTOM_MODE_ENABLED:
        return CommandOutcome(CommandResult.DENIED, "set mode: param1 needs CUSTOM_MODE_ENABLED")
    try:
        mode = SimMode(int(msg.param2)) if math.isfinite(msg.param2) else None
    except ValueError:
        mode = None
    if mode is None:
        return CommandOutcome(CommandResult.DENIED, f"set mode: unknown mode {msg.param2:g}")
    if mode is SimMode.DISARMED:
        return _outcome(autopilot.disarm(index), "mode DISARMED")
    if mode is SimMode.TAKEOFF:
        return CommandOutcome(CommandResult.DENIED, "set mode: take off with NAV_TAKEOFF")
    if mode is SimMode.HOLD:
        return _outcome(autopilot.hold(index), "mode HOLD")
    if mode is SimMode.OFFBOARD:
        return _outcome(autopilot.start_offboard(index), "mode OFFBOARD")
    return _outcome(autopilot.land(index), "mode LAND")


def _outcome(result: RequestOutcome, what: str) -> CommandOutcome:
    if result.accepted:
        return _ACCEPTED
    assert result.denial is not None
    retry = result.denial is Denial.NO_POSE
    code = CommandResult.TEMPORARILY_REJECTED if retry else CommandResult.DENIED
    return CommandOutcome(code, f"{what} denied: {result.denial.value}")
