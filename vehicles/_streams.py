"""Which telemetry messages a vehicle streams, how often, and when each is next due.

Why: a GCS sets rates with ``MAV_CMD_SET_MESSAGE_INTERVAL`` and expects them
kept in the vehicle's own time. The schedule runs on sim time, so a run at ten
times real speed streams ten times as many messages per wall second, as the
vehicle would. Messages are sent at the host's step boundaries; a rate above
the step rate is delivered once per step.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from enum import Enum
from types import MappingProxyType

from gcs.wire import mavlink

__all__ = ["DEFAULT_RATES_HZ", "IntervalRequest", "StreamSchedule", "TelemetryMessage"]


class TelemetryMessage(Enum):
    """Messages the simulated vehicle sends by itself, streamed or on request
    (``MAV_CMD_REQUEST_MESSAGE``); the value is the MAVLink message id."""

    HEARTBEAT = mavlink.MAVLINK_MSG_ID_HEARTBEAT
    LOCAL_POSITION_NED = mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED
    ATTITUDE = mavlink.MAVLINK_MSG_ID_ATTITUDE
    ATTITUDE_QUATERNION = mavlink.MAVLINK_MSG_ID_ATTITUDE_QUATERNION
    ATTITUDE_TARGET = mavlink.MAVLINK_MSG_ID_ATTITUDE_TARGET
    HIGHRES_IMU = mavlink.MAVLINK_MSG_ID_HIGHRES_IMU
    SYS_STATUS = mavlink.MAVLINK_MSG_ID_SYS_STATUS
    GPS_RAW_INT = mavlink.MAVLINK_MSG_ID_GPS_RAW_INT
    GLOBAL_POSITION_INT = mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT
    HOME_POSITION = mavlink.MAVLINK_MSG_ID_HOME_POSITION
    GPS_GLOBAL_ORIGIN = mavlink.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN
    AUTOPILOT_VERSION = mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION


DEFAULT_RATES_HZ: Mapping[TelemetryMessage, float] = MappingProxyType({
    TelemetryMessage.HEARTBEAT: 1.0,
    TelemetryMessage.LOCAL_POSITION_NED: 50.0,
    TelemetryMessage.ATTITUDE: 50.0,
    TelemetryMessage.ATTITUDE_QUATERNION: 10.0,
    TelemetryMessage.ATTITUDE_TARGET: 10.0,
    TelemetryMessage.HIGHRES_IMU: 10.0,
    TelemetryMessage.SYS_STATUS: 2.0,
    TelemetryMessage.GPS_RAW_INT: 5.0,
    TelemetryMessage.GLOBAL_POSITION_INT: 10.0,
    TelemetryMessage.HOME_POSITION: 0.0,
    TelemetryMessage.GPS_GLOBAL_ORIGIN: 0.0,
    TelemetryMessage.AUTOPILOT_VERSION: 0.0,
})
"""Rates (Hz of sim time) until the GCS asks otherwise; 0 means not streamed (HOME_POSITION
and GPS_GLOBAL_ORIGIN go out when they change, all three on request)."""


class IntervalRequest(Enum):
    """Outcome of a SET_MESSAGE_INTERVAL request."""

    SET = "rate set"
    NOT_STREAMED = "not a message this vehicle sends"
    BAD_INTERVAL = "interval must be -1, 0 or > 0 us"


class StreamSchedule:
    """Next due time of every streamed message (sim time, s); not thread-safe."""

    def __init__(self, rates_hz: Mapping[TelemetryMessage, float] = DEFAULT_RATES_HZ) -> None:
        for message, rate in rates_hz.items():
            if not (math.isfinite(rate) and rate >= 0.0):
                raise ValueError(f"{message.name}: rate must be >= 0 Hz, got {rate}")
        self._defaults = {m: float(rates_hz.get(m, 0.0)) for m in TelemetryMessage}
        self._period = {m: _period(r) for m, r in self._defaults.items()}
        self._next = dict.fromkeys(TelemetryMessage, 0.0)
        self._soonest = 0.0  # no message is due before this: most steps end here

    def set_interval(self, message_id: int, interval_us: float, t: float) -> IntervalRequest:
        """Apply ``MAV_CMD_SET_MESSAGE_INTERVAL`` (param1 message id, param2 interval) at ``t``."""
        try:
            message = TelemetryMessage(int(message_id))
        except (ValueError, OverflowError):
            return IntervalRequest.NOT_STREAMED
        if not math.isfinite(interval_us) or (interval_us < 0 and interval_us != -1):
            return IntervalRequest.BAD_INTERVAL
        if interval_us == -1:
            self._period[message] = None
        elif interval_us == 0:
            self._period[message] = _period(self._defaults[message])
        else:
            self._period[message] = interval_us / 1e6
        self._next[message] = t
        self._soonest = min(self._soonest, t)
        return IntervalRequest.SET

    def sent(self, message: TelemetryMessage, t: float) -> None:
        """``message`` went out at ``t`` out of schedule (e.g. a HEARTBEAT on a mode change)."""
        period = self._period[message]
        if period is not None:
            self._next[message] = t + period

    def due(self, t: float) -> list[TelemetryMessage]:
        """Messages due at ``t``, each rescheduled (one message after a gap, never a burst)."""
        if t < self._soonest:
            return []
        out = []
        soonest = math.inf
        for message, period in self._period.items():
            if period is None:
                continue
            if t >= self._next[message]:
                following = self._next[message] + period
                self._next[message] = following if following > t else t + period
                out.append(message)
            soonest = min(soonest, self._next[message])
        self._soonest = soonest
        return out


def _period(rate_hz: float) -> float | None:
    return None if rate_hz == 0.0 else 1.0 / rate_hz
