"""The sim host's side of zenoh: vehicle links and tokens, clock, truth, acks and control.

Why: everything the sim process says or hears on zenoh goes through this
one object, so the keys (all from :mod:`gcs.wire.keys`) and the wire formats
are in one place and the host loop never touches zenoh directly:

=================================================  =====  ======================================
key                                                dir    payload
=================================================  =====  ======================================
``fleet/<f>/vehicle/<sysid>/mavlink/from_vehicle`` out    whole MAVLink 2 frames
``fleet/<f>/vehicle/<sysid>/mavlink/to_vehicle``   in     MAVLink 2 frames
``fleet/<f>/alive/<sysid>``                        token  liveliness, while the vehicle lives
``fleet/<f>/clock``                                out    sim time (:mod:`gcs.wire._clockwire`)
``fleet/<f>/clock/ack``                            in     lockstep ack (:mod:`gcs.wire._clockwire`)
``fleet/<f>/sim/truth``                            out    :class:`gcs.wire.SimTruth` JSON
``fleet/<f>/sim/control``                          in     :mod:`sim._faults` JSON, put or
                                                          queried (answered once queued)
=================================================  =====  ======================================

Receivers run on zenoh's threads: vehicle frames go to the host's
``on_frame`` callback, everything else is pushed into its
:class:`~sim._inbox.Inbox`. Anyone on the fabric can publish on the inbound
keys: a payload longer than its key allows (MAVLink
:data:`gcs.transport.MAVLINK_PAYLOAD_MAX`, control
:data:`sim._faults.CONTROL_MAX_BYTES`, ack :data:`gcs.wire.CLOCK_MAX_BYTES`)
is dropped before it is copied out of zenoh, and counted with every other
refused input in the host's :class:`~sim._inbox.Refusals`.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Sequence

import zenoh

from gcs.transport import (
    MAVLINK_PAYLOAD_MAX,
    ZenohSettings,
    ZenohTransport,
    bounded_payload,
    declare_alive,
    open_session,
)
from gcs.wire import (
    CLOCK_MAX_BYTES,
    SEAL_OVERHEAD,
    Sealer,
    SealError,
    SigningKey,
    SimTruth,
    Unsealer,
    decode_ack,
    encode_clock,
    keys,
)
from sim._faults import CONTROL_MAX_BYTES
from sim._inbox import ClockAck, ControlMessage, Inbox, Refusals

__all__ = ["CONTROL_TOPIC", "TRUTH_TOPIC", "HostFabric"]

TRUTH_TOPIC = "truth"
"""Sim topic of the ground truth samples."""

CONTROL_TOPIC = "control"
"""Sim topic of the control messages (kill, cut, restore)."""


class _VehicleLink:
    """One vehicle's zenoh transport and liveliness token."""

    def __init__(self, session: zenoh.Session, fleet: str, sysid: int, index: int,
                 on_frame: Callable[[int, bytes], None], refusals: Refusals) -> None:
        # Frames block rather than drop: on loopback a full queue means a busy CPU, not a
        # radio, and lost telemetry would make lockstep runs differ. A peer that goes away
        # closes its link, so nothing waits on it for long.
        self.transport = ZenohTransport(
            session, tx_key=keys.mavlink(fleet, sysid, keys.Direction.FROM_VEHICLE),
            rx_key=keys.mavlink(fleet, sysid, keys.Direction.TO_VEHICLE),
            description=f"zenoh vehicle end fleet/{fleet}/vehicle/{sysid}",
            congestion=zenoh.CongestionControl.BLOCK,
            on_oversize=lambda n: refusals.refuse(
                f"MAVLink payload for vehicle {sysid}",
                f"{n} bytes, more than {MAVLINK_PAYLOAD_MAX}"))
        self.transport.start(lambda data: on_frame(index, data))
        self.token: zenoh.LivelinessToken | None = declare_alive(session, fleet=fleet,
                                                                 sysid=sysid)

    def close(self) -> None:
        # The token first: it is what tells every watcher the vehicle is gone, at once.
        if self.token is not None:
            with contextlib.suppress(zenoh.ZError):
                self.token.undeclare()
            self.token = None
        self.transport.close()


class HostFabric:
    """Opens the host's zenoh session and declares everything; :meth:`close` undoes it."""

    def __init__(self, settings: ZenohSettings, *, fleet: str, sysids: Sequence[int],
                 inbox: Inbox, on_frame: Callable[[int, bytes], None],
                 announce_sent: bool = False, refusals: Refusals | None = None,
                 seal_key: SigningKey | None = None) -> None:
        """``on_frame(index, payload)`` runs on zenoh's threads for each vehicle's payload;
        ``refusals`` counts what is refused on the way; ``seal_key`` (the team key) seals
        the clock and truth and is required on acks and control messages
        (:mod:`gcs.wire._seal`).

        ``announce_sent`` (lockstep): every clock sample carries how many truth
        samples and how many payloads of each vehicle were published
        (:func:`gcs.wire.encode_clock`), and truth is never dropped.
        """
        self._fleet = keys.check_fleet(fleet)
        self._sysids = tuple(sysids)
        self._announce_sent = announce_sent
        self.partner: int | None = None
        """Lockstep: partner id of the GCS whose acks the host follows, named in every clock
        sample once set (:mod:`gcs.wire._clockwire`)."""
        self._sent = [0] * len(self._sysids)
        self._truth_sent = 0
        self._sent_lock = threading.Lock()  # receive threads send echoes, the loop telemetry
        self._settings = settings
        self.refusals = refusals if refusals is not None else Refusals()
        """Inputs refused (oversize payloads, malformed acks), by kind."""
        self._seal_clock = Sealer(seal_key, keys.clock(fleet))
        self._seal_truth = Sealer(seal_key, keys.sim(fleet, TRUTH_TOPIC))
        self._open_ack = Unsealer(seal_key, keys.clock_ack(fleet))
        self._open_control = Unsealer(seal_key, keys.sim(fleet, CONTROL_TOPIC))
        self._extra = SEAL_OVERHEAD if seal_key is not None else 0
        self._session = open_session(settings)
        self._links: dict[int, _VehicleLink] = {}
        self._subscribers: list[zenoh.Subscriber] = []
        self._queryables: list[zenoh.Queryable] = []
        try:
            # The clock paces the GCS loop: at real-time priority it has a queue of its
            # own, so a backlog of telemetry (which blocks) cannot crowd it out; on a
            # full queue it drops, as the next sample supersedes it anyway. Neither it
            # nor the truth is express (as the frames, gcs.transport._zenoh_transport):
            # a lone sample still leaves at once, and a write for each of 128 clock
            # samples a sim second would cost a lockstep flight a noticeable share of its
            # CPU (figures: docs/performance.md, "The sim's clock coalesced").
            self._clock = self._session.declare_publisher(
                keys.clock(fleet), congestion_control=zenoh.CongestionControl.DROP,
                priority=zenoh.Priority.REAL_TIME, express=False)
            self._truth = self._session.declare_publisher(
                keys.sim(fleet, TRUTH_TOPIC), congestion_control=(
                    zenoh.CongestionControl.BLOCK if announce_sent
                    else zenoh.CongestionControl.DROP),
                priority=zenoh.Priority.DATA_LOW, express=False)
            self._subscribers.append(self._session.declare_subscriber(
                keys.clock_ack(fleet), lambda s: self._on_ack(s, inbox)))
            self._subscribers.append(self._session.declare_subscriber(
                keys.sim(fleet, CONTROL_TOPIC), lambda s: self._take_control(s.payload, inbox)))
            self._queryables.append(self._session.declare_queryable(
                keys.sim(fleet, CONTROL_TOPIC), lambda q: self._on_control_query(q, inbox)))
            for index, sysid in enumerate(sysids):
                self._links[index] = _VehicleLink(self._session, fleet, sysid, index, on_frame,
                                                  self.refusals)
        except BaseException:
            self.close()
            raise

    @property
    def fleet(self) -> str:
        """The fleet name in every key."""
        return self._fleet

    @property
    def settings(self) -> ZenohSettings:
        """How the session joined zenoh (listen and connect endpoints)."""
        return self._settings

    def send_frame(self, index: int, frame: bytes) -> None:
        """Publish a frame of vehicle ``index`` (dropped once the vehicle is gone)."""
        link = self._links.get(index)
        if link is not None:
            if self._announce_sent:
                with self._sent_lock:  # counted with the send: a sample never announces less
                    link.transport.send(frame)
                    self._sent[index] += 1
            else:
                link.transport.send(frame)

    def oversize(self, index: int) -> int:
        """Payloads for vehicle ``index`` dropped for being too long (0 once it is gone)."""
        link = self._links.get(index)
        return 0 if link is None else link.transport.oversize

    def drop_vehicle(self, index: int) -> None:
        """Vehicle ``index`` is gone: close its link and undeclare its token."""
        link = self._links.pop(index, None)
        if link is not None:
            link.close()

    def publish_clock(self, t: float) -> None:
        """Publish the sim time (with each vehicle's payload count when announcing)."""
        if not self._announce_sent:
            self._clock.put(self._seal_clock.seal(encode_clock(t)))
            return
        with self._sent_lock:
            sent = dict(zip(self._sysids, self._sent, strict=True))
        self._clock.put(self._seal_clock.seal(encode_clock(t, self._truth_sent, sent,
                                                           self.partner)))

    def publish_truth(self, truth: SimTruth) -> None:
        """Publish one ground-truth sample."""
        self._truth.put(self._seal_truth.seal(truth.to_bytes()))
        self._truth_sent += 1  # the loop's thread only, as the clock

    def close(self) -> None:
        """Undeclare everything and close the session; idempotent. The session is closed
        whatever else fails: a process that exits with it open keeps its vehicles' tokens
        alive for the peers until zenoh's lease runs out (seconds)."""
        try:
            for index in list(self._links):
                self.drop_vehicle(index)
            for sub in self._subscribers:
                with contextlib.suppress(zenoh.ZError):
                    sub.undeclare()
            self._subscribers.clear()
            for queryable in self._queryables:
                with contextlib.suppress(zenoh.ZError):
                    queryable.undeclare()
            self._queryables.clear()
        finally:
            with contextlib.suppress(zenoh.ZError):
                self._session.close()

    def _on_ack(self, sample: zenoh.Sample, inbox: Inbox) -> None:
        limit = CLOCK_MAX_BYTES + self._extra
        data = bounded_payload(sample, limit)
        if data is None:
            self.refusals.refuse("clock ack", f"{len(sample.payload)} bytes, more than {limit}")
            return
        try:
            inbox.put(ClockAck(*decode_ack(self._open_ack.open(data))))
        except ValueError as exc:  # SealError is one
            self.refusals.refuse("clock ack", str(exc))

    def _take_control(self, payload: zenoh.ZBytes | None, inbox: Inbox) -> str:
        """Queue a control message for the loop (which parses it and refuses the rest:
        :mod:`sim._faults`); returns ``queued`` or why it was refused here."""
        limit = CONTROL_MAX_BYTES + self._extra
        if payload is None or len(payload) > limit:
            why = "no payload" if payload is None else f"{len(payload)} bytes, more than {limit}"
            self.refusals.refuse("control message", why)
            return f"refused: {why}"
        try:
            inbox.put(ControlMessage(self._open_control.open(payload.to_bytes())))
        except SealError as exc:
            self.refusals.refuse("control message", str(exc))
            return f"refused: {exc}"
        return "queued"

    def _on_control_query(self, query: zenoh.Query, inbox: Inbox) -> None:
        """A control message sent as a query: queued as a put's is, then answered.

        Why: each subscriber has a thread of its own, so a put can reach the inbox
        after a clock ack sent later. A lockstep GCS that waits for this answer
        before acking its tick knows the message is queued first: it acts at the
        sim time the sim stands at, the same on every run.
        """
        answer = self._take_control(query.payload, inbox)
        query.reply(query.key_expr, answer.encode())
