"""The MAVLink 2 endpoint of one simulated vehicle: its system id, commands, setpoints, telemetry.

Why: the GCS sees a simulated vehicle only through MAVLink, exactly as it
would see PX4 or ArduPilot, so every behaviour the GCS relies on (the
contract in ``gcs/link/README.md``) lives here, between the bytes and the
:class:`~vehicles.Autopilot`:

- a MAVLink 2 system with its own system id, component 1; frames addressed
  to another system or component are counted and ignored, bad bytes are
  counted and dropped (the decoder never raises);
- PX4's identity: HEARTBEAT as PX4 sends it (autopilot PX4, its custom main
  and sub modes, :mod:`vehicles._px4_modes`; 1 Hz, and at once after every mode
  change), AUTOPILOT_VERSION on request, mode changes by DO_SET_MODE or SET_MODE
  with PX4's modes;
- telemetry at rates set by ``SET_MESSAGE_INTERVAL`` or once by
  ``REQUEST_MESSAGE`` (:mod:`vehicles._streams`), times from sim time; GPS_RAW_INT
  and GLOBAL_POSITION_INT from the world's geodetic reference, HOME_POSITION
  (where it last armed) and GPS_GLOBAL_ORIGIN (its local origin) whenever they
  change; SET_GPS_GLOBAL_ORIGIN re-bases the local frame while disarmed;
- the parameter protocol (:mod:`vehicles._params`): PARAM_REQUEST_LIST,
  PARAM_REQUEST_READ and PARAM_SET, each answered by PARAM_VALUE;
- COMMAND_LONG answered by COMMAND_ACK (:mod:`vehicles._commands`), refusals
  explained by STATUSTEXT; a retry (``confirmation`` > 0) of the command just
  carried out gets the same answer without being carried out again (a resent
  NAV_TAKEOFF whose ack was lost must not climb again from where the first
  one got to), unless the first was TEMPORARILY_REJECTED; COMMAND_INT is
  answered UNSUPPORTED, as a GCS expects an answer;
- acceleration setpoints checked (:mod:`vehicles._setpoint_check`), each
  accepted one echoed at once as POSITION_TARGET_LOCAL_NED (PX4's target
  report), each refused one reported by STATUSTEXT and never flown;
- TIMESYNC probes answered with the vehicle's clock;
- optional MAVLink 2 signing: everything sent is signed, unsigned or wrongly
  signed frames are refused.

The endpoint owns no thread and no socket. Received bytes go through two
steps: :meth:`VehicleEndpoint.take` runs on whatever thread received them
(thread-safe): it decodes, checks each setpoint and sends its echo or refusal
at once, so a setpoint's round trip never waits for a chunk of physics;
:meth:`VehicleEndpoint.apply` runs on the host's loop between chunks and hands
the accepted setpoints to the autopilot and answers commands, so the
simulation changes only at well-defined sim times. :meth:`VehicleEndpoint.receive`
does both, for single-threaded callers. The loop calls
:meth:`VehicleEndpoint.update` after each chunk of physics; frames go out
through the ``send`` callable, which must be thread-safe.
"""

from __future__ import annotations

import struct
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TypeAlias

from gcs.wire import (
    OFFBOARD_LOST_TEXT,
    AccelSetpoint,
    CommandResult,
    DecodeStats,
    FrameDecoder,
    Geodetic,
    MavlinkEncoder,
    MavMessage,
    SetpointKind,
    Severity,
    SigningKey,
    SimMode,
    geodetic_to_ned,
    mavlink,
    ned_to_geodetic,
    split_px4_custom_mode,
)
from vehicles._autopilot import Autopilot
from vehicles._battery import Battery
from vehicles._commands import CommandOutcome, execute_command, request_mode
from vehicles._params import ParamTable
from vehicles._px4_modes import Px4Modes
from vehicles._reports import (
    CommCounters,
    Home,
    Identity,
    VehicleView,
    build_report,
    time_boot_ms,
)
from vehicles._setpoint_check import Refusal, SetpointLimits, check_setpoint
from vehicles._state import Measurements
from vehicles._streams import DEFAULT_RATES_HZ, StreamSchedule, TelemetryMessage

__all__ = ["COMPONENT_ID", "DEFAULT_REFERENCE", "EndpointCounters", "Inbound",
           "VehicleEndpoint"]

COMPONENT_ID = 1
"""Component id of the simulated autopilot (``MAV_COMP_ID_AUTOPILOT1``)."""

DEFAULT_REFERENCE = Geodetic(52.0, 4.37, 0.0)
"""Geodetic position of the sensor frame's origin unless told otherwise (Delft, sea level)."""

_PARAMS_PER_PAYLOAD = 10
"""PARAM_VALUE frames per payload when every parameter is listed."""

_STATUSTEXT_LEN = 50
_OFFBOARD, _HOLD = int(SimMode.OFFBOARD), int(SimMode.HOLD)
_REFUSAL_REPORT_PERIOD = 1.0
"""At most one STATUSTEXT per refusal reason per this much sim time, s (all are counted)."""

_PARAMS = struct.Struct("<7f")
"""COMMAND_LONG's seven parameters as sent (float32)."""



@dataclass(frozen=True)
class EndpointCounters:
    """What the endpoint has seen since it started (a snapshot)."""

    decode: DecodeStats
    """The decoder's counters: frames, garbage bytes, bad checksums, truncated frames..."""
    not_for_us: int
    """Frames addressed to another system id or component, ignored."""
    commands: int
    """COMMAND_LONG answered."""
    setpoints_accepted: int
    setpoints_refused: int


Inbound: TypeAlias = AccelSetpoint | MavMessage
"""What :meth:`VehicleEndpoint.take` leaves for the loop: an accepted setpoint or a message."""


class VehicleEndpoint:
    """MAVLink 2 system ``sysid`` for vehicle ``index`` of ``autopilot``.

    Arguments (keyword-only after ``index``):
        sysid: the vehicle's MAVLink system id, 1..255.
        measurements: the world's live sensor arrays (HIGHRES_IMU reads them).
        send: called with each outgoing frame (bytes); must not block.
        signing_key: sign everything and refuse unsigned frames (None: unsigned).
        battery: the vehicle's battery (default: a full Bebop 2 pack).
        rates_hz: initial telemetry rates, Hz of sim time.
        limits: setpoint input limits.
        wall_clock: time source for signature timestamps, s since the epoch.
        reference: geodetic position of the origin of the frame the position sensor
            measures in (the world's NED origin).
        gps_accuracy_m: position accuracy the GNSS reports in GPS_RAW_INT, m.
    """

    def __init__(self, autopilot: Autopilot, index: int, *, sysid: int,
                 measurements: Measurements, send: Callable[[bytes], None],
                 signing_key: SigningKey | None = None, battery: Battery | None = None,
                 rates_hz: Mapping[TelemetryMessage, float] = DEFAULT_RATES_HZ,
                 limits: SetpointLimits | None = None,
                 wall_clock: Callable[[], float] = time.time,
                 reference: Geodetic = DEFAULT_REFERENCE,
                 gps_accuracy_m: float = 0.01) -> None:
        if not 0 <= index < autopilot.n_vehicles:
            raise IndexError(f"vehicle index {index} outside 0..{autopilot.n_vehicles - 1}")
        self._autopilot = autopilot
        self._index = index
        self._measurements = measurements
        self._send = send
        self._encoder = MavlinkEncoder(system_id=sysid, component_id=COMPONENT_ID,
                                       signing_key=signing_key, wall_clock=wall_clock)
        self._decoder = FrameDecoder(datagram=True, signing_key=signing_key,
                                     wall_clock=wall_clock)
        self._battery = battery if battery is not None else Battery()
        self._streams = StreamSchedule(rates_hz)
        self._limits = limits if limits is not None else SetpointLimits()
        self._identity = Identity(sysid, Geodetic(*reference).check("reference"),
                                  gps_accuracy_m)
        self._modes = Px4Modes(autopilot, index)
        self._params = ParamTable(autopilot, index, sysid=sysid)
        self._reported_mode: int | None = None
        """Autopilot mode (a :class:`~gcs.wire.SimMode` value) the last HEARTBEAT showed."""
        self._reported_custom: int | None = None
        """PX4 custom mode the last HEARTBEAT showed."""
        self._home: Home | None = None
        """Where the vehicle first had a position, then where it last armed (loop thread)."""
        self._was_armed = False
        self._reported_origin: tuple[float, ...] | None = None
        """Local origin (sensor frame) the last GPS_GLOBAL_ORIGIN showed."""
        self._last_update: float | None = None
        self._refusal_reported: dict[Refusal, float] = {}
        self._statustext_id = 0
        self._batch: list[MavMessage] | None = None
        """Messages held back during :meth:`update` to go out as one payload (loop thread)."""
        self._send_lock = threading.Lock()
        """Sequence numbers are given at encoding: encode and send as one step, or a
        receive thread's echo could overtake a telemetry batch and look like a loss."""
        self._rx_lock = threading.Lock()
        """Decoder, counters and refusal reports: :meth:`take` runs on receive threads."""
        self._text_lock = threading.Lock()
        self._not_for_us = 0
        self._commands = 0
        self._accepted = 0
        self._refused = 0
        self._last_command: tuple[tuple[object, ...], CommandOutcome] | None = None
        """The last COMMAND_LONG carried out: sender, command, parameters and outcome (loop
        thread); a retry is recognised against it alone, however late it comes."""
        self._handlers: dict[str, Callable[[MavMessage, float], None]] = {
            "COMMAND_LONG": self._command_long,
            "COMMAND_INT": self._command_int,
            "TIMESYNC": self._timesync,
            "SET_MODE": self._set_mode,
            "PARAM_REQUEST_LIST": self._param_request_list,
            "PARAM_REQUEST_READ": self._param_request_read,
            "PARAM_SET": self._param_set,
            "SET_GPS_GLOBAL_ORIGIN": self._set_gps_global_origin,
        }

    @property
    def sysid(self) -> int:
        """The vehicle's MAVLink system id."""
        return self._encoder.system_id

    def counters(self) -> EndpointCounters:
        """Snapshot of the counters."""
        with self._rx_lock:
            return EndpointCounters(self._decoder.stats(), self._not_for_us, self._commands,
                                    self._accepted, self._refused)

    # -- inbound --------------------------------------------------------------------------------

    def receive(self, data: bytes, t: float) -> None:
        """Act on the frames in ``data`` (one datagram or zenoh payload) at sim time ``t``."""
        self.apply(self.take(data, t), t)

    def take(self, data: bytes, t: float,
             hand_over: Callable[[list[Inbound]], None] | None = None) -> list[Inbound]:
        """Decode ``data``; echo or refuse each setpoint now; the rest for :meth:`apply`.

        Thread-safe; ``t`` is the sim time the echo is stamped with. ``hand_over``
        gets what is left for the loop *before* the echoes leave: a lockstep GCS
        acks the clock once it has the echoes, and the loop must have the
        setpoints by then.
        """
        out: list[Inbound] = []
        outgoing: list[MavMessage] = []  # echoes and refusals, sent once the lock is free
        with self._rx_lock:
            for msg in self._decoder.feed(data):
                kind = msg.get_type()
                if kind != "SET_POSITION_TARGET_LOCAL_NED" and kind not in self._handlers:
                    continue
                if not self._addressed_to_me(msg):
                    self._not_for_us += 1
                elif kind == "SET_POSITION_TARGET_LOCAL_NED":
                    setpoint = self._check(msg, t, outgoing)
                    if setpoint is not None:
                        out.append(setpoint)
                        outgoing.append(self._echo(msg, t))
                else:
                    out.append(msg)
        if out and hand_over is not None:
            hand_over(out)
        if outgoing:
            self._send_now(*outgoing)
        return out

    def apply(self, inbound: Sequence[Inbound], t: float) -> None:
        """Fly the accepted setpoints and answer the messages :meth:`take` left; loop thread."""
        for item in inbound:
            if isinstance(item, AccelSetpoint):
                if item.kind is SetpointKind.ACCEL:
                    self._autopilot.set_accel_setpoint(self._index, item.accel_ned)
                else:
                    assert item.z_ned is not None
                    self._autopilot.set_accel_xy_pos_z_setpoint(self._index, item.accel_ned[:2],
                                                                item.z_ned)
            else:
                self._handlers[item.get_type()](item, t)

    def _addressed_to_me(self, msg: MavMessage) -> bool:
        target = getattr(msg, "target_system", 0)
        component = getattr(msg, "target_component", 0)
        return target in (0, self.sysid) and component in (0, COMPONENT_ID)

    def _command_long(self, msg: MavMessage, t: float) -> None:
        with self._rx_lock:
            self._commands += 1
        # parameters compared bit for bit: NaN (QGC's and MAVSDK's "unset") equals itself
        key = (msg.get_srcSystem(), msg.get_srcComponent(), msg.command, _PARAMS.pack(
            msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6,
            msg.param7))
        last = self._last_command
        if (msg.confirmation > 0 and last is not None and last[0] == key
                and last[1].result is not CommandResult.TEMPORARILY_REJECTED):
            outcome = last[1]  # a retry whose first copy was carried out: the same answer
        else:
            outcome = execute_command(msg, self._modes, self._streams, t)
            self._last_command = (key, outcome)
            if outcome.result is not CommandResult.ACCEPTED and outcome.reason:
                self._status_text(Severity.WARNING, outcome.reason)
        self._ack(msg, outcome.result)
        if outcome.reply is not None:
            self._emit_report(outcome.reply, t)
        self._report_changes(t)

    def _set_mode(self, msg: MavMessage, t: float) -> None:
        """The SET_MODE message, as PX4 takes it: a DO_SET_MODE, acknowledged as one."""
        outcome = request_mode(self._modes, msg.base_mode,
                               *split_px4_custom_mode(msg.custom_mode))
        if outcome.result is not CommandResult.ACCEPTED and outcome.reason:
            self._status_text(Severity.WARNING, outcome.reason)
        self._emit(self._encoder.mav.command_ack_encode(
            mavlink.MAV_CMD_DO_SET_MODE, int(outcome.result), 0, 0, msg.get_srcSystem(),
            msg.get_srcComponent()))
        self._report_changes(t)

    # -- parameters and origin ------------------------------------------------------------------

    def _param_value(self, index: int) -> MavMessage:
        p = self._params[index]
        return self._encoder.mav.param_value_encode(
            p.name.encode(), self._params.wire_value(index), int(p.kind), self._params.count,
            index)

    def _param_request_list(self, msg: MavMessage, t: float) -> None:
        values = [self._param_value(k) for k in range(self._params.count)]
        for start in range(0, len(values), _PARAMS_PER_PAYLOAD):
            self._send_now(*values[start:start + _PARAMS_PER_PAYLOAD])

    def _param_request_read(self, msg: MavMessage, t: float) -> None:
        """By index when ``param_index`` is not -1, else by name."""
        if msg.param_index >= 0:
            index = msg.param_index if msg.param_index < self._params.count else None
            what = f"index {msg.param_index}"
        else:
            index = self._params.index_of(msg.param_id)
            what = repr(msg.param_id)
        if index is None:
            self._status_text(Severity.WARNING, f"param read: no parameter {what}")
        else:
            self._emit(self._param_value(index))

    def _param_set(self, msg: MavMessage, t: float) -> None:
        """Apply it; answer what the parameter holds now (the old value when refused)."""
        result = self._params.set(msg.param_id, msg.param_value, msg.param_type)
        if result.refusal:
            self._status_text(Severity.WARNING, f"param set refused: {result.refusal}")
        if result.index is not None:
            self._emit(self._param_value(result.index))

    def _set_gps_global_origin(self, msg: MavMessage, t: float) -> None:
        """Re-base the local frame on the given origin (only while disarmed, as ArduPilot);
        answered by GPS_GLOBAL_ORIGIN with the origin in force afterwards."""
        origins = self._autopilot.state.origin_ned
        before = tuple(origins[self._index])
        try:
            origin = Geodetic(msg.latitude / 1e7, msg.longitude / 1e7,
                              msg.altitude / 1e3).check("SET_GPS_GLOBAL_ORIGIN")
        except ValueError as exc:
            self._status_text(Severity.WARNING, f"origin not changed: {exc}")
        else:
            outcome = self._autopilot.set_origin(
                self._index, geodetic_to_ned(origin, self._identity.reference))
            if not outcome.accepted:
                self._status_text(Severity.WARNING, f"origin not changed: {outcome.text}")
        now = tuple(origins[self._index])
        self._report_changes(t)  # a new origin (and home) once the vehicle has a position
        if now == before or self._reported_origin != now:  # else not answered yet
            self._emit_report(TelemetryMessage.GPS_GLOBAL_ORIGIN, t)

    def _command_int(self, msg: MavMessage, t: float) -> None:
        """No command is taken in COMMAND_INT form here: say so rather than stay silent."""
        with self._rx_lock:
            self._commands += 1
        self._ack(msg, CommandResult.UNSUPPORTED)

    def _ack(self, msg: MavMessage, result: CommandResult) -> None:
        self._emit(self._encoder.mav.command_ack_encode(
            msg.command, int(result), 0, 0, msg.get_srcSystem(), msg.get_srcComponent()))

    def _check(self, msg: MavMessage, t: float,
               reports: list[MavMessage]) -> AccelSetpoint | None:
        """The setpoint if acceptable; refuse the rest (their STATUSTEXT into ``reports``)."""
        verdict = check_setpoint(msg, self._limits)
        setpoint = verdict.setpoint
        if setpoint is None:
            self._refused += 1
            assert verdict.refusal is not None
            last = self._refusal_reported.get(verdict.refusal)
            if last is None or t - last >= _REFUSAL_REPORT_PERIOD:
                self._refusal_reported[verdict.refusal] = t
                reports.extend(self._status_text_messages(Severity.WARNING, verdict.text))
            return None
        self._accepted += 1
        return setpoint

    def _echo(self, msg: MavMessage, t: float) -> MavMessage:
        """PX4's target report of an accepted setpoint (the autopilot flies it next chunk)."""
        return self._encoder.mav.position_target_local_ned_encode(
            time_boot_ms(t), msg.coordinate_frame, msg.type_mask, msg.x, msg.y, msg.z, msg.vx,
            msg.vy, msg.vz, msg.afx, msg.afy, msg.afz, msg.yaw, msg.yaw_rate)

    def _timesync(self, msg: MavMessage, t: float) -> None:
        if msg.tc1 == 0:  # a probe; non-zero tc1 is someone's answer, not for us
            self._emit(self._encoder.mav.timesync_encode(int(t * 1e9), msg.ts1))

    # -- outbound -------------------------------------------------------------------------------

    def update(self, t: float) -> None:
        """After physics reached sim time ``t``: drain the battery, send what is due.

        What is due goes out as one payload (several whole frames, as every MAVLink
        datagram reader accepts): one zenoh put costs as much as encoding a frame.
        """
        if self._last_update is not None:
            kf = self._autopilot.airframe.thrust_coefficient
            rotor_speed = self._autopilot.state.rotor_speed_model[self._index].tolist()
            self._battery.draw([kf * w * w for w in rotor_speed], t - self._last_update)
        self._last_update = t
        messages: list[MavMessage] = []
        self._batch = messages
        try:
            self._report_failsafe()
            self._report_changes(t)
            due = self._streams.due(t)
            if due:
                view = self._view(t, with_comm=TelemetryMessage.SYS_STATUS in due)
                for message in due:
                    report = build_report(self._encoder.mav, message, view)
                    if report is not None:
                        self._emit(report)
        finally:
            self._batch = None
        if messages:
            self._send_now(*messages)

    def _report_failsafe(self) -> None:
        """Say why the vehicle left OFFBOARD on its own, as PX4 announces a failsafe: between
        commands only the setpoint timeout moves OFFBOARD to HOLD (a command's mode change
        is reported as it is handled). A ground station tells a lost stream from a pilot's
        switch by it."""
        mode = int(self._autopilot.state.mode[self._index])
        if self._reported_mode == _OFFBOARD and mode == _HOLD:
            self._status_text(Severity.WARNING, OFFBOARD_LOST_TEXT)

    def _report_changes(self, t: float) -> None:
        """Send at once what changed: the mode (HEARTBEAT), home (HOME_POSITION: set at the
        first position sample and at each arming) and the local origin (GPS_GLOBAL_ORIGIN)."""
        state, i = self._autopilot.state, self._index
        mode, custom = int(state.mode[i]), self._modes.custom_mode()
        if (mode, custom) != (self._reported_mode, self._reported_custom):
            self._reported_mode, self._reported_custom = mode, custom
            self._emit_report(TelemetryMessage.HEARTBEAT, t)
        if state.pose_seq_seen[i] == 0:
            return
        armed = mode != SimMode.DISARMED
        new_home = self._home is None or (armed and not self._was_armed)
        self._was_armed = armed
        if new_home:
            here = state.p_est[i] + state.origin_ned[i]
            self._home = Home(here, Geodetic(*(float(v) for v in ned_to_geodetic(
                here, self._identity.reference))))
        origin = tuple(state.origin_ned[i])
        moved = origin != self._reported_origin
        if moved:
            self._reported_origin = origin
            self._emit_report(TelemetryMessage.GPS_GLOBAL_ORIGIN, t)
        if new_home or moved:  # the home's local coordinates move with the origin
            self._emit_report(TelemetryMessage.HOME_POSITION, t)

    def _emit_report(self, message: TelemetryMessage, t: float) -> None:
        """Send ``message`` now, out of its schedule."""
        view = self._view(t, with_comm=message is TelemetryMessage.SYS_STATUS)
        report = build_report(self._encoder.mav, message, view)
        if report is not None:
            self._emit(report)
            self._streams.sent(message, t)

    def _view(self, t: float, *, with_comm: bool) -> VehicleView:
        comm = None
        if with_comm:  # only SYS_STATUS reads them; a snapshot of the decoder is not free
            c = self.counters()
            comm = CommCounters(frames=c.decode.frames, dropped=c.decode.dropped,
                                not_for_us=c.not_for_us, garbage_bytes=c.decode.garbage_bytes,
                                setpoints_refused=c.setpoints_refused)
        return VehicleView(self._autopilot, self._index, self._measurements,
                           self._battery.reading(), comm, t, self._identity,
                           self._modes.custom_mode(), self._home)

    def _status_text(self, severity: Severity, text: str) -> None:
        """Send a STATUSTEXT (loop thread)."""
        for msg in self._status_text_messages(severity, text):
            self._emit(msg)

    def _status_text_messages(self, severity: Severity, text: str) -> list[MavMessage]:
        """STATUSTEXT, split into MAVLink 2 chunks (same id, rising chunk_seq) when long."""
        data = text.encode("utf-8")
        mav = self._encoder.mav
        if len(data) <= _STATUSTEXT_LEN:
            return [mav.statustext_encode(int(severity), data)]
        with self._text_lock:
            self._statustext_id = text_id = self._statustext_id % 0xFFFF + 1
        # A final chunk shorter than 50 bytes (possibly empty) tells receivers the text ended.
        return [mav.statustext_encode(int(severity), data[start:start + _STATUSTEXT_LEN],
                                      text_id, seq)
                for seq, start in enumerate(range(0, len(data) + 1, _STATUSTEXT_LEN))]

    def _emit(self, msg: MavMessage) -> None:
        """Send ``msg``, or hold it for the batch :meth:`update` is building (loop thread)."""
        if self._batch is not None:
            self._batch.append(msg)
        else:
            self._send_now(msg)

    def _send_now(self, *messages: MavMessage) -> None:
        """Encode ``messages`` and send them as one payload, in sequence order (any thread)."""
        with self._send_lock:
            self._send(b"".join(self._encoder.encode(m) for m in messages))
