"""MAVLink frames over zenoh, and vehicle liveliness tokens.

Each vehicle has two keys (see :mod:`gcs.wire.keys`): the GCS publishes on
``to_vehicle`` and subscribes to ``from_vehicle``; the vehicle endpoint does
the reverse. One zenoh payload carries whole encoded frames.

Publications are not ``express``: zenoh then coalesces whatever is queued
while the link is busy into one write instead of one write per frame, so a
tick's setpoints publish many times faster and the sim's telemetry does not
block its loop, which shortens the setpoint round trip (figures:
docs/performance.md, bench/link_latency.py, bench/gcs_tick.py); an idle link
still sends a lone frame at once.

Anyone on the fabric can publish on a vehicle's keys: a payload longer than
:data:`MAVLINK_PAYLOAD_MAX` is dropped before it is copied out of zenoh, and
counted (``oversize``): 10 MB of MAVLink start bytes, each a candidate frame,
keep a decoder busy and slow the sim while they come (figures:
docs/performance.md).
"""

from __future__ import annotations

import contextlib
import logging
import threading
from collections.abc import Callable, Mapping

import zenoh

from gcs.transport._arrivals import Arrivals
from gcs.wire import keys

__all__ = ["MAVLINK_PAYLOAD_MAX", "FleetReceiver", "ZenohTransport", "bounded_payload",
           "declare_alive", "watch_alive"]

_log = logging.getLogger(__name__)

MAVLINK_PAYLOAD_MAX = 65_535
"""Longest payload taken on a vehicle's MAVLink key, bytes: what a UDP datagram can hold
(a vehicle's telemetry of one step is about 1 kB, a frame at most 280 bytes)."""


def bounded_payload(sample: zenoh.Sample, limit: int) -> bytes | None:
    """The sample's payload, or None, without copying it, if it is longer than ``limit``."""
    payload = sample.payload
    if len(payload) > limit:
        return None
    return payload.to_bytes()


class FleetReceiver:
    """One subscriber for every vehicle's frames of a fleet in one direction.

    Why: zenoh-python runs each callback subscriber on a Python thread of its own,
    so a hundred links with a subscriber each are a hundred threads contending
    for the GIL with the 4 Hz loop. This one subscriber hands each payload to the
    transport registered for the system id in its key.
    """

    def __init__(self, session: zenoh.Session, *, fleet: str, direction: keys.Direction,
                 max_payload: int = MAVLINK_PAYLOAD_MAX) -> None:
        self._direction = direction
        self._max_payload = max_payload
        self.oversize = 0
        """Payloads dropped for being longer than ``max_payload`` bytes."""
        self._oversize_of: dict[int, int] = {}
        self._handlers: dict[int, Callable[[bytes], None]] = {}
        self._arrivals = Arrivals()  # payloads per system id, registered or not
        self._subscriber: zenoh.Subscriber | None = session.declare_subscriber(
            keys.mavlink_all(fleet, direction), self._deliver)

    def register(self, sysid: int, on_bytes: Callable[[bytes], None]) -> None:
        """Deliver vehicle ``sysid``'s payloads to ``on_bytes`` (zenoh's thread)."""
        if sysid in self._handlers:
            raise RuntimeError(f"vehicle {sysid} already has a receiver")
        self._handlers = {**self._handlers, sysid: on_bytes}  # replaced whole: read lock-free

    def oversize_of(self, sysid: int) -> int:
        """Payloads of vehicle ``sysid`` dropped for being too long."""
        return self._oversize_of.get(sysid, 0)

    def unregister(self, sysid: int) -> None:
        """Stop delivering vehicle ``sysid``'s payloads."""
        self._handlers = {k: v for k, v in self._handlers.items() if k != sysid}

    def close(self) -> None:
        """Undeclare the subscriber; idempotent."""
        sub, self._subscriber = self._subscriber, None
        if sub is not None:
            with contextlib.suppress(zenoh.ZError):  # session closed: nothing to undeclare
                sub.undeclare()

    def _deliver(self, sample: zenoh.Sample) -> None:
        parsed = keys.parse_mavlink(str(sample.key_expr))
        if parsed is None or parsed[1] is not self._direction:
            return
        sysid = parsed[0]
        handler = self._handlers.get(sysid)
        if handler is not None:
            data = bounded_payload(sample, self._max_payload)
            if data is None:
                self.oversize += 1
                self._oversize_of[sysid] = self._oversize_of.get(sysid, 0) + 1
            else:
                handler(data)
        self._arrivals.arrived(sysid)  # after the handler: a waiter goes on once it is in

    def wait_received(self, sent: Mapping[int, int], timeout_s: float) -> bool:
        """Block until the registered vehicles' payloads counted in ``sent`` are all handled.

        ``sent``: payloads each system id has published so far (a lockstep sim's
        clock sample, :func:`gcs.wire.decode_clock`); see
        :meth:`gcs.transport.Arrivals.wait`.
        """
        return self._arrivals.wait(sent, timeout_s, only=lambda s: s in self._handlers)


class ZenohTransport:
    """A :class:`~gcs.transport.Transport` over one zenoh session (shared, not owned)."""

    def __init__(self, session: zenoh.Session, *, tx_key: str, rx_key: str,
                 description: str | None = None,
                 congestion: zenoh.CongestionControl = zenoh.CongestionControl.DROP,
                 priority: zenoh.Priority = zenoh.Priority.DATA,
                 receiver: FleetReceiver | None = None,
                 max_payload: int = MAVLINK_PAYLOAD_MAX,
                 on_oversize: Callable[[int], object] | None = None) -> None:
        """``receiver``: receive through a shared :class:`FleetReceiver` (for the system
        id in ``rx_key``, which bounds the payloads itself) instead of a subscriber of this
        transport's own. ``priority``: zenoh queues each priority apart, so a higher one is
        not stuck behind a backlog of lower ones. ``max_payload``: longer payloads
        received are dropped and counted (:attr:`oversize`), and ``on_oversize(length)``
        is told of each (on zenoh's thread; without a ``receiver``)."""
        self._session = session
        self._receiver = receiver
        parsed = keys.parse_mavlink(rx_key)
        if receiver is not None and parsed is None:
            raise ValueError(f"{rx_key!r} is not a vehicle MAVLink key")
        self._rx_sysid = parsed[0] if parsed is not None else None
        self._tx_key = tx_key
        self._rx_key = rx_key
        self._description = description or f"zenoh {tx_key} / {rx_key}"
        self._publisher: zenoh.Publisher | None = session.declare_publisher(
            tx_key, congestion_control=congestion, priority=priority, express=False)
        self._subscriber: zenoh.Subscriber | None = None
        self._started = False
        self._lock = threading.Lock()
        # Held around every put and while the publisher is taken away: zenoh-python's
        # undeclare raises "Already borrowed" while another thread is inside put (a sim
        # vehicle killed while its receive thread echoes a frame would crash the sim).
        self._send_lock = threading.Lock()
        self.callback_errors = 0
        """Exceptions raised by the receive callback (logged, then counted)."""
        self._max_payload = max_payload
        self._oversize = 0
        self._on_oversize = on_oversize

    @classmethod
    def for_gcs(cls, session: zenoh.Session, *, fleet: str, sysid: int,
                receiver: FleetReceiver | None = None) -> ZenohTransport:
        """The GCS end of vehicle ``sysid``'s link.

        Commands and setpoints are few and must not vanish in a congested queue
        (two lost setpoints put a vehicle in hold), so they block rather than drop,
        and go at interactive priority, ahead of any bulk data on the same link.
        """
        return cls(session, tx_key=keys.mavlink(fleet, sysid, keys.Direction.TO_VEHICLE),
                   rx_key=keys.mavlink(fleet, sysid, keys.Direction.FROM_VEHICLE),
                   description=f"zenoh fleet/{fleet}/vehicle/{sysid}",
                   congestion=zenoh.CongestionControl.BLOCK,
                   priority=zenoh.Priority.INTERACTIVE_HIGH, receiver=receiver)

    @classmethod
    def for_vehicle(cls, session: zenoh.Session, *, fleet: str, sysid: int) -> ZenohTransport:
        """The vehicle end of vehicle ``sysid``'s link (used by the sim)."""
        return cls(session, tx_key=keys.mavlink(fleet, sysid, keys.Direction.FROM_VEHICLE),
                   rx_key=keys.mavlink(fleet, sysid, keys.Direction.TO_VEHICLE),
                   description=f"zenoh vehicle end fleet/{fleet}/vehicle/{sysid}")

    @property
    def datagram(self) -> bool:
        """Zenoh payloads hold whole frames."""
        return True

    @property
    def oversize(self) -> int:
        """Payloads for this link received and dropped for being too long."""
        if self._receiver is not None:
            assert self._rx_sysid is not None
            return self._receiver.oversize_of(self._rx_sysid)
        return self._oversize

    @property
    def description(self) -> str:
        """The keys this transport uses."""
        return self._description

    def start(self, on_bytes: Callable[[bytes], None]) -> None:
        """Subscribe; ``on_bytes`` runs on zenoh's callback threads."""
        def deliver(data: bytes) -> None:
            try:
                on_bytes(data)
            except Exception:
                self.callback_errors += 1
                _log.exception("MAVLink receive callback failed on %s", self._rx_key)

        with self._lock:
            if self._started or self._publisher is None:
                raise RuntimeError(f"{self._description}: already started or closed")
            if self._receiver is not None:
                assert self._rx_sysid is not None
                self._receiver.register(self._rx_sysid, deliver)
            else:
                self._subscriber = self._session.declare_subscriber(
                    self._rx_key, lambda sample: self._bounded(sample, deliver))
            self._started = True

    def _bounded(self, sample: zenoh.Sample, deliver: Callable[[bytes], None]) -> None:
        data = bounded_payload(sample, self._max_payload)
        if data is None:
            self._oversize += 1
            if self._on_oversize is not None:
                self._on_oversize(len(sample.payload))
        else:
            deliver(data)

    def send(self, frame: bytes) -> None:
        """Publish one payload (any thread); dropped silently after close."""
        with self._send_lock:
            publisher = self._publisher
            if publisher is None:
                return
            try:
                publisher.put(frame)
            except zenoh.ZError:  # session closed underneath us: a lost frame, as on a radio
                _log.debug("zenoh put failed on %s", self._tx_key)

    def close(self) -> None:
        """Undeclare the subscriber and publisher (the session stays open); safe while
        other threads send (a put in progress ends first, later ones are dropped)."""
        with self._lock:
            with self._send_lock:
                sub, pub = self._subscriber, self._publisher
                self._subscriber = self._publisher = None
            if self._started and self._receiver is not None and pub is not None:
                assert self._rx_sysid is not None
                self._receiver.unregister(self._rx_sysid)
        for entity in (sub, pub):
            if entity is not None:
                with contextlib.suppress(zenoh.ZError):  # session closed: nothing to undeclare
                    entity.undeclare()


def declare_alive(session: zenoh.Session, *, fleet: str, sysid: int) -> zenoh.LivelinessToken:
    """Declare vehicle ``sysid``'s liveliness token; gone when undeclared or the session ends.

    Keep the returned token referenced for as long as the vehicle is up:
    zenoh undeclares a token that is garbage-collected.
    """
    return session.liveliness().declare_token(keys.alive(fleet, sysid))


def watch_alive(session: zenoh.Session, *, fleet: str,
                on_change: Callable[[int, bool], object]) -> zenoh.Subscriber:
    """Call ``on_change(sysid, alive)`` when a vehicle token of ``fleet`` appears or vanishes.

    Tokens that already exist are reported at once (history). Runs on zenoh's
    threads; undeclare the returned subscriber to stop.
    """
    def deliver(sample: zenoh.Sample) -> None:
        sysid = keys.parse_alive(str(sample.key_expr))
        if sysid is None:
            return
        try:
            on_change(sysid, sample.kind == zenoh.SampleKind.PUT)
        except Exception:
            _log.exception("liveliness callback failed for vehicle %s", sysid)

    return session.liveliness().declare_subscriber(keys.alive_all(fleet), deliver, history=True)
