"""The GCS's link to one vehicle: MAVLink in and out, latest telemetry, health, commands.

A :class:`Link` talks to exactly one target system id over one transport.
Frames from any other system id are counted and ignored. Received messages
update the telemetry records on the transport's thread; the GCS loop reads
snapshots (:attr:`Link.telemetry`, :attr:`Link.health`) from its own thread.

In the background the link sends the GCS ``HEARTBEAT`` (autopilots use it for
their GCS-loss failsafe) and ``TIMESYNC`` probes whose answers give the
round-trip time. Commands block the caller until the vehicle acknowledges
them; they are serialised per link.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import NamedTuple

from gcs.common import join_thread
from gcs.link._errors import CommandAck, CommandError, CommandResult, LinkError
from gcs.link._health import LinkHealth, SequenceTracker
from gcs.transport import FrameDirection, Transport
from gcs.wire import (
    DEFAULT_GCS_COMPONENT_ID,
    DEFAULT_GCS_SYSTEM_ID,
    SETPOINT_MESSAGE,
    DecodeStats,
    FrameDecoder,
    MavlinkEncoder,
    MavMessage,
    SigningKey,
    Telemetry,
    TelemetryRecord,
    TelemetryStore,
    accel_setpoint_fields,
    mavlink,
    message_id,
)

__all__ = ["DEFAULT_TELEMETRY_RATES_HZ", "Link", "Outbound"]

_log = logging.getLogger(__name__)

DEFAULT_TELEMETRY_RATES_HZ: Mapping[str, float] = MappingProxyType({
    "LOCAL_POSITION_NED": 20.0,
    "ATTITUDE": 20.0,
    "SYS_STATUS": 1.0,
    "ATTITUDE_TARGET": 4.0,
})
"""What the GCS reads from a real autopilot, Hz, and asks it for when first heard
(:meth:`Link.request_telemetry`): position and velocity for the guidance (five samples per
4 Hz tick) and ArduPilot's vertical loop, attitude for tilt and the rope pull estimate,
SYS_STATUS for the battery, the collective thrust for load sharing (one per tick).
Nothing more: a telemetry radio's bandwidth is shared."""


class _PendingCommand:
    """A command waiting for its acknowledgement."""

    __slots__ = ("acks", "command")

    def __init__(self, command: int) -> None:
        self.command = command
        self.acks: deque[CommandResult] = deque()


class Outbound(NamedTuple):
    """A link's sending side, for a sender that numbers and sends its frames in a batch."""

    transport: Transport
    """The link's carrier: its ``send`` takes one frame (looked up at each send)."""
    closed: threading.Event
    """Set once the link is closed: its frames are then not sent."""
    listened: Sequence[object]
    """The link's frame listeners (live): when not empty, :meth:`Link.sent` each frame."""


class Link:
    """MAVLink link from the GCS to one vehicle; thread-safe.

    Use as a context manager or call :meth:`start` and :meth:`close`.
    Times in telemetry and health come from ``clock`` (wall or sim time);
    command timeouts and round-trip times are real (monotonic) time.
    """

    def __init__(self, sysid: int, transport: Transport, *,
                 gcs_system_id: int = DEFAULT_GCS_SYSTEM_ID,
                 gcs_component_id: int = DEFAULT_GCS_COMPONENT_ID,
                 target_component: int = 1,
                 signing_key: SigningKey | None = None, signing_link_id: int = 0,
                 clock: Callable[[], float] = time.monotonic,
                 command_timeout_s: float = 1.0, command_retries: int = 2,
                 command_in_progress_timeout_s: float = 10.0,
                 heartbeat_timeout_s: float = 3.0,
                 gcs_heartbeat_period_s: float = 1.0, timesync_period_s: float = 1.0,
                 service_offset_s: float = 0.0,
                 send_lock: threading.Lock | None = None) -> None:
        if isinstance(sysid, bool) or not isinstance(sysid, int) or not 1 <= sysid <= 255:
            raise ValueError(f"vehicle system id must be an integer 1..255, got {sysid!r}")
        if sysid == gcs_system_id:
            raise ValueError(f"vehicle system id {sysid} equals the GCS's own system id")
        if command_timeout_s <= 0 or command_retries < 0 or heartbeat_timeout_s <= 0:
            raise ValueError("command_timeout_s and heartbeat_timeout_s must be positive, "
                             "command_retries at least 0")
        self._sysid = sysid
        self._target_component = target_component
        self._transport = transport
        self._encoder = MavlinkEncoder(system_id=gcs_system_id, component_id=gcs_component_id,
                                       signing_key=signing_key, link_id=signing_link_id)
        self._decoder = FrameDecoder(datagram=transport.datagram, signing_key=signing_key)
        self._signed = signing_key is not None
        self._clock = clock
        self._command_timeout_s = command_timeout_s
        self._command_retries = command_retries
        self._in_progress_timeout_s = command_in_progress_timeout_s
        self._heartbeat_timeout_s = heartbeat_timeout_s
        self._heartbeat_period_s = gcs_heartbeat_period_s
        self._timesync_period_s = timesync_period_s
        self._t0 = time.monotonic()
        self._next_heartbeat = self._next_timesync = self._t0 + service_offset_s

        self._rx_lock = threading.Lock()  # the decoder; held only while decoding
        self._cond = threading.Condition()  # everything below
        self._store = TelemetryStore(sysid)
        self._seq = SequenceTracker()
        self._received = 0
        self._wrong_system = 0
        self._foreign: set[int] = set()
        self._rtt_s: float | None = None
        self._pending: _PendingCommand | None = None
        self._timesync_sent: deque[int] = deque(maxlen=16)

        self._command_lock = threading.Lock()
        # Links that a Fanout sends to together share one (see LinkManager).
        self._send_lock = send_lock if send_lock is not None else threading.Lock()
        self._message_listeners: list[Callable[[MavMessage], None]] = []
        self._record_listeners: list[Callable[[TelemetryRecord], None]] = []
        self._frame_listeners: list[Callable[[FrameDirection, bytes], None]] = []
        self._pause: Callable[[], bool] | None = None
        self._stop = threading.Event()
        self._started = False
        self._service: threading.Thread | None = None

    # -- life cycle -----------------------------------------------------------------------

    def start(self, *, background: bool = True) -> Link:
        """Start receiving and the periodic HEARTBEAT/TIMESYNC; returns self.

        ``background=False`` leaves the periodic frames to the caller, who calls
        :meth:`service` now and then (a manager of a hundred links runs one
        thread for all of them instead of a hundred threads waking together).
        """
        if self._started:
            raise LinkError(self._sysid, "link already started")
        self._started = True
        self._transport.start(self._on_bytes)
        if background and (self._heartbeat_period_s > 0 or self._timesync_period_s > 0):
            self._service = threading.Thread(target=self._service_loop, daemon=True,
                                             name=f"link-{self._sysid}-service")
            self._service.start()
        return self

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return self._stop.is_set()

    def close(self) -> None:
        """Stop background work and close the transport; idempotent."""
        if self._stop.is_set():
            return
        self._stop.set()
        join_thread(self._service, 2.0, what=f"the link service of vehicle {self.sysid}")
        self._transport.close()
        with self._rx_lock:
            self._decoder.flush()

    def __enter__(self) -> Link:
        return self.start() if not self._started else self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    # -- identity and snapshots ---------------------------------------------------------------

    @property
    def sysid(self) -> int:
        """The vehicle's system id."""
        return self._sysid

    @property
    def target_component(self) -> int:
        """The vehicle autopilot's component id."""
        return self._target_component

    @property
    def gcs_system_id(self) -> int:
        """The GCS's own system id on this link."""
        return self._encoder.system_id

    @property
    def description(self) -> str:
        """The transport's description."""
        return self._transport.description

    @property
    def transport(self) -> Transport:
        """The transport this link owns."""
        return self._transport

    @property
    def clock(self) -> Callable[[], float]:
        """The clock that stamps telemetry (s)."""
        return self._clock

    @property
    def telemetry(self) -> Telemetry:
        """Consistent snapshot of the latest telemetry (a new one on every read)."""
        with self._cond:
            return self._store.snapshot()

    @property
    def rtt_s(self) -> float | None:
        """Latest round-trip time (TIMESYNC or COMMAND_ACK), s; None before the first."""
        return self._rtt_s

    @property
    def health(self) -> LinkHealth:
        """Snapshot of the link's health (a new one on every read)."""
        with self._rx_lock:
            stats = self._decoder.stats()
        now = self._clock()
        with self._cond:
            hb = self._store.heartbeat
            age = None if hb is None else max(0.0, now - hb.received_at)
            return LinkHealth(
                sysid=self._sysid, heartbeat_age_s=age,
                alive=age is not None and age < self._heartbeat_timeout_s,
                frames_received=self._received, frames_sent=self._encoder.frames_sent,
                packets_lost=self._seq.lost, refused_bad_crc=stats.bad_crc,
                refused_signature=stats.refused_signature,
                refused_wrong_system=self._wrong_system,
                foreign_systems=tuple(sorted(self._foreign)),
                garbage_bytes=stats.garbage_bytes, truncated=stats.truncated, rtt_s=self._rtt_s,
                refused_values=self._store.refused, signed=self._signed,
                refused_oversize=int(getattr(self._transport, "oversize", 0)))

    def decode_stats(self) -> DecodeStats:
        """The decoder's raw counters."""
        with self._rx_lock:
            return self._decoder.stats()

    def wait_for(self, predicate: Callable[[Telemetry], bool], *, timeout_s: float,
                 what: str) -> Telemetry:
        """Block until ``predicate(telemetry)`` holds; LinkError naming ``what`` on timeout."""
        deadline = time.monotonic() + timeout_s
        # Gated (lockstep): look only at ticks, the first time at the next one, so the
        # answer does not depend on whether a message in flight has arrived yet.
        gated = self._pause is not None and self._pause()
        while True:
            with self._cond:
                snapshot = self._store.snapshot()
                if predicate(snapshot):
                    return snapshot
                remaining = deadline - time.monotonic()
                if remaining <= 0 or self._stop.is_set():
                    raise LinkError(self._sysid, f"timed out after {timeout_s:g} s waiting "
                                                 f"for {what}")
                if not gated:
                    self._cond.wait(remaining)
                    continue
            gated = self._pause is not None and self._pause()

    def set_pause(self, pause: Callable[[], bool] | None) -> None:
        """Make :meth:`wait_for` wait with ``pause`` (True: waited for the next tick).

        Why: in lockstep with the simulator the waits of phase actions must end
        at ticks, not at whatever wall time a message happens to arrive
        (:class:`gcs.loop.StepGate`). ``pause`` answering False falls back to
        waiting on the link, as when none is set.
        """
        self._pause = pause

    # -- listeners ------------------------------------------------------------------------------

    def add_message_listener(self, callback: Callable[[MavMessage], None]) -> None:
        """Call ``callback(msg)`` for every message from the vehicle (on the receive thread)."""
        self._message_listeners.append(callback)

    def add_record_listener(self, callback: Callable[[TelemetryRecord], None]) -> None:
        """Call ``callback(record)`` with every new telemetry record (on the receive thread).

        Why: a fleet-wide table kept current here lets the loop read a hundred
        vehicles at once instead of taking a snapshot of each link per tick.
        """
        self._record_listeners.append(callback)

    def add_frame_listener(self, callback: Callable[[FrameDirection, bytes], None]) -> None:
        """Call ``callback(direction, frame)`` for every accepted frame in and every frame out.

        Incoming frames from other system ids are included (a recorder wants them).
        Outgoing frames are handed over under the send lock, so a recorder sees
        them in sequence order; that lock is shared by the links of one
        :class:`~gcs.link.LinkManager`, so the callback must be quick and
        must never send (it would wait for the lock it runs under).
        """
        self._frame_listeners.append(callback)

    # -- sending --------------------------------------------------------------------------------

    @property
    def mav(self) -> mavlink.MAVLink:
        """pymavlink message factory for :meth:`send_message`."""
        return self._encoder.mav

    def send_message(self, msg: MavMessage) -> None:
        """Encode (and sign) ``msg`` as the GCS and send it; non-blocking."""
        self._send_frame(self._encoder.encode, msg)

    @property
    def boot_time(self) -> float:
        """Monotonic time (s) that the ``time_boot_ms`` of the GCS's frames counts from."""
        return self._t0

    @property
    def encoder(self) -> MavlinkEncoder:
        """The encoder that numbers (and signs) the GCS's frames to this vehicle; number
        frames with it only under :attr:`send_lock` (:class:`~gcs.link.Fanout` does)."""
        return self._encoder

    @property
    def send_lock(self) -> threading.Lock:
        """The lock under which a frame is numbered and sent (shared by the links of one
        :class:`~gcs.link.LinkManager`): the vehicle then sees no gap in the sequence."""
        return self._send_lock

    def send_stamped(self, frame: bytes) -> None:
        """Send ``frame``, already numbered by :attr:`encoder`, and hand it to the frame
        listeners; the caller holds :attr:`send_lock`. LinkError if the link is closed."""
        if self._stop.is_set():
            raise LinkError(self._sysid, "link is closed")
        self._transport.send(frame)
        self.sent(frame)

    def outbound(self) -> Outbound:
        """What a batch sender needs to send this link's numbered frames itself, with no
        call per frame (:class:`~gcs.link.Fanout`: a fleet's setpoints each tick)."""
        return Outbound(transport=self._transport, closed=self._stop,
                        listened=self._frame_listeners)

    def sent(self, frame: bytes) -> None:
        """Hand ``frame``, just sent under :attr:`send_lock`, to the frame listeners."""
        for listener in self._frame_listeners:
            self._call(listener, FrameDirection.OUT, frame)

    def _send_frame(self, encode: Callable[..., bytes], *args: object) -> None:
        if self._stop.is_set():
            raise LinkError(self._sysid, "link is closed")
        # The loop, the service thread and commands all send: encoding gives the
        # sequence number, so encode and send as one step or the vehicle sees a loss.
        with self._send_lock:  # listeners too: the recorder keeps frames in sequence order
            self.send_stamped(encode(*args))

    def send_setpoint(self, *, accel_xy_ned: tuple[float, float], z_ned: float | None = None,
                      az_ned: float | None = None) -> None:
        """Send an acceleration setpoint: x/y acceleration (m/s^2) and z (m) or az (m/s^2), NED.

        See :mod:`gcs.wire._setpoints`; which vertical channel to use is the
        autopilot profile's choice.
        """
        values = accel_setpoint_fields(
            target_system=self._sysid, target_component=self._target_component,
            time_boot_ms=self._time_boot_ms(), accel_xy_ned=accel_xy_ned, z_ned=z_ned,
            az_ned=az_ned)
        self._send_frame(self._encoder.encode_fields, SETPOINT_MESSAGE, *values)

    def send_timesync(self) -> None:
        """Send a TIMESYNC probe; its answer updates the round-trip time."""
        ts1 = time.monotonic_ns()
        with self._cond:
            self._timesync_sent.append(ts1)
        self.send_message(self._encoder.mav.timesync_encode(0, ts1))

    def command_long(self, command: int, params: Sequence[float] = (), *,
                     timeout_s: float | None = None, retries: int | None = None) -> CommandAck:
        """Send ``COMMAND_LONG`` and block until it is accepted.

        Unanswered attempts are re-sent (``confirmation`` counts them) up to
        ``retries`` times; TEMPORARILY_REJECTED is retried too; IN_PROGRESS
        extends the wait to ``command_in_progress_timeout_s``. Raises
        :class:`CommandError` for any other result or when no acknowledgement
        arrives. Never call it from a listener: those run on the receive thread.
        """
        if len(params) > 7:
            raise ValueError(f"COMMAND_LONG has 7 parameters, got {len(params)}")
        p = [float(v) for v in params] + [0.0] * (7 - len(params))
        timeout = self._command_timeout_s if timeout_s is None else timeout_s
        attempts_max = 1 + (self._command_retries if retries is None else retries)
        pending = _PendingCommand(command)
        with self._command_lock:
            with self._cond:
                self._pending = pending
            try:
                for attempt in range(attempts_max):
                    msg = self._encoder.mav.command_long_encode(
                        self._sysid, self._target_component, command, min(attempt, 255), *p)
                    sent_at = time.monotonic()
                    self.send_message(msg)
                    result = self._await_ack(pending, timeout)
                    if result is None:
                        continue
                    if result is CommandResult.ACCEPTED:
                        rtt = time.monotonic() - sent_at
                        with self._cond:
                            self._rtt_s = rtt
                        return CommandAck(command, result, attempt + 1, rtt)
                    if result is CommandResult.TEMPORARILY_REJECTED and attempt + 1 < attempts_max:
                        self._stop.wait(min(timeout, 0.2))
                        continue
                    raise CommandError(self._sysid, command, result, attempts=attempt + 1,
                                       timeout_s=timeout)
                raise CommandError(self._sysid, command, CommandResult.TIMEOUT,
                                   attempts=attempts_max, timeout_s=timeout)
            finally:
                with self._cond:
                    self._pending = None

    def set_message_interval(self, message: str | int, *, rate_hz: float,
                             timeout_s: float | None = None,
                             retries: int | None = None) -> CommandAck:
        """Ask for ``message`` (name or id) at ``rate_hz`` (0: stop) by SET_MESSAGE_INTERVAL."""
        msg_id = message_id(message) if isinstance(message, str) else int(message)
        if rate_hz < 0:
            raise ValueError(f"rate_hz must be >= 0, got {rate_hz}")
        interval_us = -1.0 if rate_hz == 0 else 1e6 / rate_hz
        return self.command_long(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL,
                                 (float(msg_id), interval_us), timeout_s=timeout_s,
                                 retries=retries)

    def request_telemetry(self, rates_hz: Mapping[str, float] = DEFAULT_TELEMETRY_RATES_HZ, *,
                          timeout_s: float | None = None,
                          retries: int | None = None) -> dict[str, CommandResult]:
        """Set several message rates; returns each message's result instead of raising.

        Autopilots do not all stream every message (ArduPilot has no
        HIGHRES_IMU), so a refusal is reported, not fatal.
        """
        results: dict[str, CommandResult] = {}
        for name, rate in rates_hz.items():
            try:
                results[name] = self.set_message_interval(name, rate_hz=rate,
                                                          timeout_s=timeout_s,
                                                          retries=retries).result
            except CommandError as exc:
                results[name] = exc.result
        return results

    # -- receiving ------------------------------------------------------------------------------

    def _on_bytes(self, data: bytes) -> None:
        with self._rx_lock:
            messages = self._decoder.feed(data)
        if not messages:
            return
        now = self._clock()
        replies: list[MavMessage] = []
        mine: list[MavMessage] = []
        records: list[TelemetryRecord] = []
        with self._cond:
            for msg in messages:
                if self._accept(msg, now, replies, records):
                    mine.append(msg)
            self._cond.notify_all()
        for msg in messages:
            for frame_listener in self._frame_listeners:
                self._call(frame_listener, FrameDirection.IN, bytes(msg.get_msgbuf()))
        for record in records:
            for record_listener in self._record_listeners:
                self._call(record_listener, record)
        for msg in mine:
            for listener in self._message_listeners:
                self._call(listener, msg)
        for reply in replies:
            try:
                self.send_message(reply)
            except LinkError:
                break  # closed meanwhile

    def _accept(self, msg: MavMessage, now: float, replies: list[MavMessage],
                records: list[TelemetryRecord]) -> bool:
        """Account one message under the lock; False if it is not from the vehicle."""
        src = msg.get_srcSystem()
        if src != self._sysid:
            self._wrong_system += 1
            self._foreign.add(src)
            return False
        self._received += 1
        self._seq.update(src, msg.get_srcComponent(), msg.get_seq())
        if msg.get_srcComponent() != self._target_component:
            return True
        kind = msg.get_type()
        if kind == "COMMAND_ACK":
            pending = self._pending
            target = getattr(msg, "target_system", 0)
            if pending is not None and msg.command == pending.command and target in (
                    0, self._encoder.system_id):
                pending.acks.append(CommandResult.from_wire(msg.result))
        elif kind == "TIMESYNC":
            if msg.tc1 == 0:  # the vehicle probes us: answer with our time
                replies.append(self._encoder.mav.timesync_encode(time.monotonic_ns(), msg.ts1))
            elif msg.ts1 in self._timesync_sent:
                self._timesync_sent.remove(msg.ts1)
                self._rtt_s = (time.monotonic_ns() - msg.ts1) / 1e9
        else:
            record = self._store.update(msg, now)
            if record is not None:
                records.append(record)
        return True

    def _await_ack(self, pending: _PendingCommand, timeout_s: float) -> CommandResult | None:
        deadline = time.monotonic() + timeout_s
        with self._cond:
            while True:
                while pending.acks:
                    result = pending.acks.popleft()
                    if result is CommandResult.IN_PROGRESS:  # accepted, still running
                        deadline = time.monotonic() + max(timeout_s, self._in_progress_timeout_s)
                        continue
                    return result
                remaining = deadline - time.monotonic()
                if remaining <= 0 or self._stop.is_set():
                    return None
                self._cond.wait(remaining)

    # -- background -----------------------------------------------------------------------------

    def service(self, now: float | None = None) -> float:
        """Send the HEARTBEAT and TIMESYNC that are due; the next due time (monotonic s).

        Returns ``inf`` when neither is configured or the link is closed.
        """
        now = time.monotonic() if now is None else now
        try:
            if self._heartbeat_period_s > 0 and now >= self._next_heartbeat:
                self.send_message(self._encoder.mav.heartbeat_encode(
                    mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0,
                    mavlink.MAV_STATE_ACTIVE))
                # on the schedule, not from a late call (a shared thread serves in steps)
                self._next_heartbeat = max(self._next_heartbeat + self._heartbeat_period_s, now)
            if self._timesync_period_s > 0 and now >= self._next_timesync:
                self.send_timesync()
                self._next_timesync = max(self._next_timesync + self._timesync_period_s, now)
        except LinkError:
            return math.inf  # closed meanwhile
        return min((t for t, period in ((self._next_heartbeat, self._heartbeat_period_s),
                                        (self._next_timesync, self._timesync_period_s))
                    if period > 0), default=math.inf)

    def _service_loop(self) -> None:
        while not self._stop.is_set():
            due = self.service()
            if math.isinf(due):
                return
            self._stop.wait(max(0.0, due - time.monotonic()))

    def _time_boot_ms(self) -> int:
        return int((time.monotonic() - self._t0) * 1000.0)

    def _call(self, callback: Callable[..., None], *args: object) -> None:
        try:
            callback(*args)
        except Exception:
            _log.exception("link %d listener %r failed", self._sysid, callback)
