"""COMMAND_LONG of a simulated vehicle: what each command does and its COMMAND_ACK result.

Why: the GCS's autopilot profile (``gcs.link._profile_sim``) drives the
vehicle with exactly these commands and confirms each step, and other ground
stations drive it as they drive PX4, so every command must map onto one
:class:`~vehicles.Autopilot` action (or one message sent back) and answer
with the result a real autopilot would give:

===============================  ========================================================
command                          effect
===============================  ========================================================
COMPONENT_ARM_DISARM             param1 1 arm, 0 disarm (param2 21196 forces it in flight)
NAV_TAKEOFF                      climb param7 m above the current position (NaN:
                                 ``takeoff_altitude``, PX4's MIS_TAKEOFF_ALT), then HOLD
NAV_LAND                         land where the vehicle is, disarm on touchdown
DO_SET_MODE                      param1 with CUSTOM_MODE_ENABLED, param2/param3 a PX4 main
                                 and sub mode (:func:`gcs.wire.sim_mode_for_px4`)
SET_MESSAGE_INTERVAL             param1 message id, param2 interval in us (-1 stop, 0 default)
REQUEST_MESSAGE                  param1 message id: that message once, after the ack
REQUEST_AUTOPILOT_CAPABILITIES   param1 1: AUTOPILOT_VERSION after the ack
GET_HOME_POSITION                HOME_POSITION after the ack
anything else                    UNSUPPORTED
===============================  ========================================================

Refusals are DENIED, except arming before the first position sample and
asking for a position before there is one, which are TEMPORARILY_REJECTED
(the GCS retries); each refusal also has a reason for a STATUSTEXT.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gcs.wire import (
    CUSTOM_MODE_ENABLED,
    CommandResult,
    MavMessage,
    SimMode,
    mavlink,
    px4_custom_mode,
    px4_mode_text,
    sim_mode_for_px4,
)
from vehicles._autopilot import Autopilot
from vehicles._outcomes import Denial, RequestOutcome
from vehicles._px4_modes import Px4Modes
from vehicles._streams import IntervalRequest, StreamSchedule, TelemetryMessage

__all__ = ["FORCE_DISARM_MAGIC", "CommandOutcome", "execute_command", "request_mode"]

FORCE_DISARM_MAGIC = 21196
"""COMPONENT_ARM_DISARM param2 that disarms even in flight (the MAVLink convention)."""

_NEEDS_POSITION = frozenset({TelemetryMessage.GLOBAL_POSITION_INT,
                             TelemetryMessage.HOME_POSITION})


@dataclass(frozen=True)
class CommandOutcome:
    """Result for the COMMAND_ACK, the reason for a STATUSTEXT when refused, and the message
    to send after the ack when the command asked for one."""

    result: CommandResult
    reason: str = ""
    reply: TelemetryMessage | None = None


_ACCEPTED = CommandOutcome(CommandResult.ACCEPTED)


def execute_command(msg: MavMessage, modes: Px4Modes, streams: StreamSchedule,
                    t: float) -> CommandOutcome:
    """Carry out one COMMAND_LONG for the vehicle behind ``modes`` at sim time ``t``."""
    command = msg.command
    autopilot, index = modes.autopilot, modes.index
    if command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
        return _arm_disarm(msg, autopilot, index)
    if command == mavlink.MAV_CMD_NAV_TAKEOFF:
        return _takeoff(msg.param7, autopilot, index)
    if command == mavlink.MAV_CMD_NAV_LAND:
        return _outcome(autopilot.land(index), "land")
    if command == mavlink.MAV_CMD_DO_SET_MODE:
        if not all(math.isfinite(p) for p in (msg.param1, msg.param2, msg.param3)):
            return CommandOutcome(CommandResult.DENIED, "set mode: parameters not finite")
        return request_mode(modes, int(msg.param1), int(msg.param2), int(msg.param3))
    if command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
        request = streams.set_interval(int(msg.param1) if math.isfinite(msg.param1) else -1,
                                       msg.param2, t)
        if request is IntervalRequest.SET:
            return _ACCEPTED
        return CommandOutcome(CommandResult.DENIED, f"interval: {request.value}")
    if command == mavlink.MAV_CMD_REQUEST_MESSAGE:
        return _request_message(msg.param1, autopilot, index)
    if command == mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES:
        if msg.param1 != 1.0:
            return CommandOutcome(CommandResult.DENIED, "capabilities: param1 must be 1")
        return CommandOutcome(CommandResult.ACCEPTED, reply=TelemetryMessage.AUTOPILOT_VERSION)
    if command == mavlink.MAV_CMD_GET_HOME_POSITION:
        return _request_message(TelemetryMessage.HOME_POSITION.value, autopilot, index)
    return CommandOutcome(CommandResult.UNSUPPORTED)


def request_mode(modes: Px4Modes, base_mode: int, main: int, sub: int) -> CommandOutcome:
    """Switch to PX4 mode (main, sub), as DO_SET_MODE or the SET_MODE message ask."""
    if not base_mode & CUSTOM_MODE_ENABLED:
        return CommandOutcome(CommandResult.DENIED, "set mode: needs CUSTOM_MODE_ENABLED")
    autopilot, index = modes.autopilot, modes.index
    mode = sim_mode_for_px4(main, sub)
    if mode is None:
        name = px4_mode_text(px4_custom_mode(main, sub)) if 0 < main < 256 and 0 <= sub < 256 \
            else f"{main}.{sub}"
        return CommandOutcome(CommandResult.DENIED,
                              f"set mode: {name} is not a mode of this vehicle")
    if mode is SimMode.TAKEOFF:
        return _takeoff(math.nan, autopilot, index)
    if mode is SimMode.LAND:
        return _outcome(autopilot.land(index), "mode LAND")
    if mode is SimMode.OFFBOARD:
        return _outcome(autopilot.start_offboard(index), "mode OFFBOARD")
    outcome = _outcome(autopilot.hold(index), "mode HOLD")
    if outcome.result is CommandResult.ACCEPTED:
        modes.held_as(main, sub)
    return outcome


def _arm_disarm(msg: MavMessage, autopilot: Autopilot, index: int) -> CommandOutcome:
    if msg.param1 == 1.0:
        return _outcome(autopilot.arm(index), "arm")
    if msg.param1 == 0.0:
        return _outcome(autopilot.disarm(index, force=msg.param2 == FORCE_DISARM_MAGIC),
                        "disarm")
    return CommandOutcome(CommandResult.DENIED, f"arm: param1 must be 0 or 1, got {msg.param1:g}")


def _takeoff(climb_m: float, autopilot: Autopilot, index: int) -> CommandOutcome:
    """NAV_TAKEOFF param7 is the climb above the current position (see gcs.link._profile_sim);
    NaN, as PX4 ground stations send it, climbs the configured take-off altitude."""
    if math.isnan(climb_m):
        climb_m = autopilot.vehicle_config(index).takeoff_altitude
    if not math.isfinite(climb_m) or climb_m <= 0.0:
        return CommandOutcome(CommandResult.DENIED, "takeoff: param7 must be a climb > 0 m")
    state = autopilot.state
    height = float(state.z_home[index] - state.p_est[index, 2]) if autopilot.armed[index] else 0.0
    return _outcome(autopilot.takeoff(index, max(0.0, height) + climb_m), "takeoff")


def _request_message(message_id: float, autopilot: Autopilot, index: int) -> CommandOutcome:
    try:
        message = TelemetryMessage(int(message_id)) if math.isfinite(message_id) else None
    except ValueError:
        message = None
    if message is None:
        return CommandOutcome(CommandResult.DENIED,
                              f"request: message {message_id:g} is not one this vehicle sends")
    if message in _NEEDS_POSITION and autopilot.state.pose_seq_seen[index] == 0:
        return CommandOutcome(CommandResult.TEMPORARILY_REJECTED,
                              f"request: no {message.name} before the first position fix")
    return CommandOutcome(CommandResult.ACCEPTED, reply=message)


def _outcome(result: RequestOutcome, what: str) -> CommandOutcome:
    if result.accepted:
        return _ACCEPTED
    assert result.denial is not None
    retry = result.denial is Denial.NO_POSE
    code = CommandResult.TEMPORARILY_REJECTED if retry else CommandResult.DENIED
    return CommandOutcome(code, f"{what} denied: {result.denial.value}")
