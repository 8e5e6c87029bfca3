"""Zenoh transport and discovery with real zenoh sessions on loopback.

Each test opens its own sessions on a fresh port with multicast scouting off,
so tests running side by side never see each other. The vehicle side is
built only from the link layer's shared pieces (encoder, decoder, zenoh
transport, liveliness), as the simulator's endpoint will be.
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import pytest
import zenoh
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.config import GcsLinkConfig, LinkConfig
from gcs.link import Link, LinkManager, Presence, PresenceEvent
from gcs.link._discovery import PresenceSource
from gcs.link._profile_sim import SimProfile
from gcs.transport import (
    FleetReceiver,
    ZenohSettings,
    ZenohTransport,
    declare_alive,
    open_session,
    watch_alive,
)
from gcs.wire import (
    CUSTOM_MODE_ENABLED,
    SAFETY_ARMED,
    AccelSetpoint,
    FrameDecoder,
    MavlinkEncoder,
    SimMode,
    decode_clock,
    encode_clock,
    keys,
    read_setpoint,
)
from gcs.wire._clockwire import ClockSample

FLEET = "linktest"


def free_tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@dataclass
class Fabric:
    """A listening 'sim' session and a connecting 'gcs' session."""

    sim: zenoh.Session
    gcs: zenoh.Session
    endpoint: str

    def extra_session(self) -> zenoh.Session:
        return open_session(ZenohSettings(connect=(self.endpoint,)))


@pytest.fixture
def fabric() -> Iterator[Fabric]:
    for _ in range(5):
        endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
        try:
            sim = open_session(ZenohSettings(listen=(endpoint,), connect=()))
        except RuntimeError:  # port taken between the probe and the bind
            continue
        break
    else:
        pytest.fail("no free port for zenoh")
    gcs = open_session(ZenohSettings(connect=(endpoint,)))
    yield Fabric(sim, gcs, endpoint)
    gcs.close()
    sim.close()


def eventually(condition: Callable[[], bool], what: str, timeout_s: float = 5.0,
               action: Callable[[], None] | None = None) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        if action is not None:
            action()
        time.sleep(0.02)


class ZenohVehicle:
    """A simulated vehicle's MAVLink endpoint made of the shared link-layer pieces."""

    def __init__(self, session: zenoh.Session, sysid: int) -> None:
        self.sysid = sysid
        self.encoder = MavlinkEncoder(system_id=sysid, component_id=1)
        self.decoder = FrameDecoder(datagram=True)
        self.transport = ZenohTransport.for_vehicle(session, fleet=FLEET, sysid=sysid)
        self.token: zenoh.LivelinessToken | None = declare_alive(session, fleet=FLEET,
                                                                 sysid=sysid)
        self.mode = SimMode.DISARMED
        self.armed = False
        self.z_ned = 0.0
        self.commands: list[tuple[int, float, float, float]] = []
        self.setpoints: list[AccelSetpoint] = []
        self.beating = threading.Event()
        self.beating.set()
        self._lock = threading.Lock()
        self._quit = threading.Event()
        self.transport.start(self._on_bytes)
        self._thread = threading.Thread(target=self._stream, daemon=True)
        self._thread.start()

    def send(self, msg: object) -> None:
        self.transport.send(self.encoder.encode(msg))  # type: ignore[arg-type]

    def _stream(self) -> None:
        mav = self.encoder.mav
        while not self._quit.wait(0.05):
            if self.beating.is_set():
                base = CUSTOM_MODE_ENABLED | (SAFETY_ARMED if self.armed else 0)
                self.send(mav.heartbeat_encode(v20.MAV_TYPE_QUADROTOR, v20.MAV_AUTOPILOT_GENERIC,
                                               base, int(self.mode), v20.MAV_STATE_ACTIVE))
                self.send(mav.local_position_ned_encode(0, 0.0, 0.0, self.z_ned, 0, 0, 0))

    def _on_bytes(self, data: bytes) -> None:
        with self._lock:
            messages = self.decoder.feed(data)
        for msg in messages:
            if msg.get_type() == "COMMAND_LONG":
                self.commands.append((msg.command, msg.param1, msg.param2, msg.param7))
                self.send(self.encoder.mav.command_ack_encode(
                    msg.command, self._command(msg), 0, 0, msg.get_srcSystem(),
                    msg.get_srcComponent()))
            setpoint = read_setpoint(msg)
            if setpoint is not None:
                self.setpoints.append(setpoint)

    def _command(self, msg: object) -> int:
        command = msg.command  # type: ignore[attr-defined]
        if command == v20.MAV_CMD_COMPONENT_ARM_DISARM:
            self.armed = msg.param1 == 1.0  # type: ignore[attr-defined]
        elif command == v20.MAV_CMD_NAV_TAKEOFF:
            self.mode, self.z_ned = SimMode.TAKEOFF, -msg.param7  # type: ignore[attr-defined]
        elif command == v20.MAV_CMD_DO_SET_MODE:
            self.mode = SimMode(int(msg.param2))  # type: ignore[attr-defined]
        elif command == v20.MAV_CMD_NAV_LAND:
            self.mode = SimMode.LAND
        else:
            return v20.MAV_RESULT_UNSUPPORTED
        return v20.MAV_RESULT_ACCEPTED

    def vanish(self) -> None:
        if self.token is not None:
            self.token.undeclare()
            self.token = None

    def close(self) -> None:
        self._quit.set()
        self._thread.join(timeout=2.0)
        self.transport.close()
        self.vanish()


def test_key_expressions_are_the_documented_ones() -> None:
    assert keys.mavlink("f", 3, keys.Direction.TO_VEHICLE) == "fleet/f/vehicle/3/mavlink/to_vehicle"
    assert (keys.mavlink("f", 3, keys.Direction.FROM_VEHICLE)
            == "fleet/f/vehicle/3/mavlink/from_vehicle")
    assert keys.alive("f", 3) == "fleet/f/alive/3"
    assert keys.clock("f") == "fleet/f/clock"
    assert keys.sim("f", "payload") == "fleet/f/sim/payload"
    assert keys.sim_all("f") == "fleet/f/sim/**"
    assert keys.parse_alive("fleet/f/alive/17") == 17
    assert keys.parse_mavlink("fleet/f/vehicle/200/mavlink/to_vehicle") == (
        200, keys.Direction.TO_VEHICLE)
    for bad in ("fleet/f/alive/0", "fleet/f/alive/256", "fleet/f/alive/03", "fleet/f/alive/x"):
        assert keys.parse_alive(bad) is None
    for fleet in ("a/b", "*", "", "a b", "$x"):
        with pytest.raises(ValueError, match="fleet name"):
            keys.alive(fleet, 1)
    with pytest.raises(ValueError, match="system id"):
        keys.alive("f", 0)
    with pytest.raises(ValueError, match="sim topic"):
        keys.sim("f", "rope/**")


def test_two_sessions_exchange_frames_under_the_documented_keys(fabric: Fabric) -> None:
    seen_by_gcs: list[tuple[str, bytes]] = []
    seen_by_sim: list[tuple[str, bytes]] = []
    fabric.gcs.declare_subscriber(
        f"fleet/{FLEET}/vehicle/3/mavlink/from_vehicle",
        lambda s: seen_by_gcs.append((str(s.key_expr), s.payload.to_bytes())))
    fabric.sim.declare_subscriber(
        f"fleet/{FLEET}/vehicle/3/mavlink/to_vehicle",
        lambda s: seen_by_sim.append((str(s.key_expr), s.payload.to_bytes())))
    vehicle_end = ZenohTransport.for_vehicle(fabric.sim, fleet=FLEET, sysid=3)
    gcs_end = ZenohTransport.for_gcs(fabric.gcs, fleet=FLEET, sysid=3)
    vehicle = MavlinkEncoder(system_id=3, component_id=1)
    gcs = MavlinkEncoder(system_id=245, component_id=190)
    up = vehicle.encode(vehicle.mav.heartbeat_encode(2, 0, 0, 1, 4))
    down = gcs.encode(gcs.mav.heartbeat_encode(6, 8, 0, 0, 4))
    try:
        eventually(lambda: bool(seen_by_gcs) and bool(seen_by_sim), "frames both ways",
                   action=lambda: (vehicle_end.send(up), gcs_end.send(down)))
    finally:
        vehicle_end.close()
        gcs_end.close()
    assert seen_by_gcs[0] == (f"fleet/{FLEET}/vehicle/3/mavlink/from_vehicle", up)
    assert seen_by_sim[0] == (f"fleet/{FLEET}/vehicle/3/mavlink/to_vehicle", down)
    (msg,) = FrameDecoder(datagram=True).feed(seen_by_gcs[0][1])
    assert (msg.get_type(), msg.get_srcSystem()) == ("HEARTBEAT", 3)


def test_a_transport_closes_while_another_thread_sends(fabric: Fabric) -> None:
    """What a killed sim vehicle does: the loop closes its link while a receive thread is
    echoing a frame. zenoh-python's undeclare raised "Already borrowed" during a put; the
    sim loop died of it (every vehicle gone, the clock stopped). 30 of 30 closes raised
    before the fix."""
    received = threading.Semaphore(0)
    fabric.gcs.declare_subscriber(f"fleet/{FLEET}/vehicle/*/mavlink/from_vehicle",
                                  lambda _: received.release())
    frame = bytes(280)
    for sysid in range(1, 31):
        transport = ZenohTransport(
            fabric.sim, tx_key=keys.mavlink(FLEET, sysid, keys.Direction.FROM_VEHICLE),
            rx_key=keys.mavlink(FLEET, sysid, keys.Direction.TO_VEHICLE),
            congestion=zenoh.CongestionControl.BLOCK)
        stop = threading.Event()
        failures: list[BaseException] = []

        def send_until_stopped(transport: ZenohTransport = transport,
                               stop: threading.Event = stop,
                               failures: list[BaseException] = failures) -> None:
            try:
                while not stop.is_set():
                    transport.send(frame)
            except BaseException as exc:  # the test reports it below
                failures.append(exc)

        sender = threading.Thread(target=send_until_stopped)
        sender.start()
        try:
            assert received.acquire(timeout=5.0), f"vehicle {sysid}: nothing sent"
            transport.close()  # mid-stream
        finally:
            stop.set()
            sender.join(timeout=5.0)
        assert failures == [], f"vehicle {sysid}: the sender failed: {failures[0]!r}"
        assert not sender.is_alive()
    transport.send(frame)  # after close: dropped, no error


def test_link_over_zenoh_with_a_simulated_vehicle(fabric: Fabric) -> None:
    vehicle = ZenohVehicle(fabric.sim, 3)
    link = Link(3, ZenohTransport.for_gcs(fabric.gcs, fleet=FLEET, sysid=3),
                command_timeout_s=0.5, timesync_period_s=0.0).start()
    try:
        link.wait_for(lambda t: t.heartbeat is not None and t.position is not None,
                      timeout_s=5.0, what="telemetry over zenoh")
        profile = SimProfile(link)
        profile.takeoff(altitude_m=1.2)
        link.wait_for(lambda t: t.position is not None and abs(t.position.p_ned[2] + 1.2) < 1e-5,
                      timeout_s=3.0, what="climb")
        profile.start_offboard()
        for _ in range(3):
            profile.send_setpoint(accel_xy_ned=(0.5, 0.25), z_ned=-1.2)
        profile.land()
        profile.disarm()
        eventually(lambda: len(vehicle.setpoints) >= 4, "setpoints")
        health = link.health
    finally:
        link.close()
        vehicle.close()
    assert [c[0] for c in vehicle.commands] == [
        v20.MAV_CMD_COMPONENT_ARM_DISARM, v20.MAV_CMD_NAV_TAKEOFF, v20.MAV_CMD_DO_SET_MODE,
        v20.MAV_CMD_NAV_LAND, v20.MAV_CMD_COMPONENT_ARM_DISARM]
    assert vehicle.commands[2][2] == SimMode.OFFBOARD
    assert vehicle.commands[1][3] == pytest.approx(1.2)
    last = vehicle.setpoints[-1]
    assert last.accel_ned[:2] == (0.5, 0.25) and last.z_ned == pytest.approx(-1.2)
    assert health.refused == 0 and health.packets_lost == 0 and health.rtt_s is not None


def test_liveliness_token_gone_within_a_second_of_session_close(fabric: Fabric) -> None:
    changes: list[tuple[float, int, bool]] = []
    watcher = watch_alive(fabric.gcs, fleet=FLEET,
                          on_change=lambda sysid, up: changes.append((time.monotonic(), sysid,
                                                                      up)))
    vehicle_process = fabric.extra_session()
    token = declare_alive(vehicle_process, fleet=FLEET, sysid=5)  # dropping it would undeclare
    try:
        eventually(lambda: (5, True) in [(s, u) for _, s, u in changes], "token appears")
        closed_at = time.monotonic()
        vehicle_process.close()
        eventually(lambda: (5, False) in [(s, u) for _, s, u in changes], "token vanishes",
                   timeout_s=1.0)
    finally:
        watcher.undeclare()
    assert token is not None
    gone_at = next(t for t, s, u in changes if s == 5 and not u)
    assert 0.0 <= gone_at - closed_at < 1.0
    assert [(s, u) for _, s, u in changes] == [(5, True), (5, False)]


def test_manager_reports_presence_and_names_missing_vehicles(fabric: Fabric) -> None:
    events: list[PresenceEvent] = []
    configs = [LinkConfig(sysid=3, heartbeat_timeout_s=0.5),
               LinkConfig(sysid=4, heartbeat_timeout_s=0.5)]
    # the stand-in vehicles do not sign: presence is the subject here, not signing
    settings = GcsLinkConfig(fleet=FLEET, timesync_period_s=0.0, signing=False)
    vehicle = ZenohVehicle(fabric.sim, 3)
    stranger = ZenohVehicle(fabric.sim, 9)
    manager = LinkManager(configs, settings=settings, session=fabric.gcs,
                          on_presence=events.append, check_period_s=0.05)

    def seen(sysid: int, presence: Presence, source: PresenceSource) -> bool:
        return any((e.sysid, e.presence, e.source) == (sysid, presence, source) for e in events)

    try:
        assert set(manager.links) == {3, 4} and manager.profiles[3].name.value == "sim"
        eventually(lambda: seen(3, Presence.APPEARED, PresenceSource.HEARTBEAT)
                   and seen(3, Presence.APPEARED, PresenceSource.LIVELINESS)
                   and seen(9, Presence.APPEARED, PresenceSource.LIVELINESS), "vehicles appear")
        assert manager.missing() == (4,)
        assert manager.discovery.missing_text() == "configured vehicles not seen: 4"
        assert next(e for e in events if e.sysid == 9).configured is False
        assert next(e for e in events if e.sysid == 3).text.startswith("vehicle 3 appeared (")

        vehicle.beating.clear()  # autopilot hangs; its process is still up
        stopped = time.monotonic()
        eventually(lambda: seen(3, Presence.VANISHED, PresenceSource.HEARTBEAT),
                   "heartbeat loss", timeout_s=2.0)
        assert time.monotonic() - stopped >= 0.4
        assert manager.missing() == (4,)  # the liveliness token still vouches for it
        vehicle.vanish()
        eventually(lambda: seen(3, Presence.VANISHED, PresenceSource.LIVELINESS),
                   "token loss", timeout_s=1.0)
        assert manager.missing() == (3, 4)
        polled = manager.discovery.events()
        assert [(e.sysid, e.presence) for e in polled] == [
            (e.sysid, e.presence) for e in events]
    finally:
        manager.close()
        vehicle.close()
        stranger.close()


def test_one_thread_sends_every_links_heartbeat_spread_over_the_period(fabric: Fabric) -> None:
    """Twenty links, no thread per link: each vehicle hears the GCS at the configured rate."""
    ids = list(range(21, 41))
    heard: dict[int, list[float]] = {sysid: [] for sysid in ids}
    decoders = {sysid: FrameDecoder(datagram=True) for sysid in ids}

    def listen(sysid: int) -> Callable[[zenoh.Sample], None]:
        def on_sample(sample: zenoh.Sample) -> None:
            for msg in decoders[sysid].feed(sample.payload.to_bytes()):
                if msg.get_type() == "HEARTBEAT" and msg.type == v20.MAV_TYPE_GCS:
                    heard[sysid].append(time.monotonic())
        return on_sample

    subs = [fabric.sim.declare_subscriber(keys.mavlink(FLEET, sysid, keys.Direction.TO_VEHICLE),
                                          listen(sysid)) for sysid in ids]
    before = threading.active_count()
    settings = GcsLinkConfig(fleet=FLEET, heartbeat_period_s=0.5, timesync_period_s=0.0)
    manager = LinkManager([LinkConfig(sysid=s) for s in ids], settings=settings,
                          session=fabric.gcs, check_period_s=0.02)
    try:
        # the manager's own thread, and zenoh-python's one per callback subscriber: the
        # fleet's frames and the liveliness watch (not one per link)
        assert threading.active_count() - before <= 3
        time.sleep(2.2)
    finally:
        manager.close()
        for sub in subs:
            sub.undeclare()
    counts = [len(heard[s]) for s in ids]
    assert min(counts) >= 3 and max(counts) <= 6, counts  # 0.5 s period over 2.2 s
    firsts = sorted(heard[s][0] for s in ids)
    assert firsts[-1] - firsts[0] > 0.3  # spread over the period, not one burst


def test_fleet_receiver_waits_for_the_payloads_a_clock_sample_announces(fabric: Fabric) -> None:
    """A lockstep sim's clock sample counts each vehicle's payloads; the GCS waits for them."""
    receiver = FleetReceiver(fabric.gcs, fleet=FLEET, direction=keys.Direction.FROM_VEHICLE)
    got: list[bytes] = []
    receiver.register(5, got.append)
    vehicle = ZenohTransport.for_vehicle(fabric.sim, fleet=FLEET, sysid=5)
    other = ZenohTransport.for_vehicle(fabric.sim, fleet=FLEET, sysid=6)  # not registered
    try:
        eventually(lambda: bool(got), "the route up", action=lambda: vehicle.send(b"x"))
        # 40 more, sent in a burst: the wait ends once the last one is handled, not before
        before = len(got)
        sample = decode_clock(encode_clock(1.0, 0, {5: before + 40, 6: 1000}))
        for k in range(40):
            vehicle.send(bytes([k]))
        assert receiver.wait_received(sample.sent, 5.0) is True
        assert len(got) == before + 40  # vehicle 6 is nobody's here: not waited for
        # two announced that never come (lost, or sent before this GCS subscribed): one
        # bounded wait, then written off
        t0 = time.monotonic()
        assert receiver.wait_received({5: before + 42}, 0.2) is False
        assert 0.15 < time.monotonic() - t0 < 2.0
        assert receiver.wait_received({5: before + 42}, 0.2) is True
        vehicle.send(b"y")
        assert receiver.wait_received({5: before + 43}, 5.0) is True
    finally:
        vehicle.close()
        other.close()
        receiver.close()


def test_clock_samples_with_and_without_payload_counts() -> None:
    assert decode_clock(encode_clock(2.5)) == ClockSample(2.5)
    assert len(encode_clock(2.5)) == 8  # the plain 8-byte sample, as acks use
    sample = decode_clock(encode_clock(0.25, 9, {1: 7, 255: 2**32 + 3}))
    assert sample == ClockSample(0.25, 9, {1: 7, 255: 3})  # counts wrap at 2^32
    assert decode_clock(encode_clock(0.5, 0)) == ClockSample(0.5, 0, {})  # no vehicle yet
    with pytest.raises(ValueError, match="8 bytes, or 12 plus 5 per vehicle, got 11"):
        decode_clock(encode_clock(1.0) + b"abc")
    with pytest.raises(ValueError, match="finite time"):
        decode_clock(encode_clock(float("nan"), 1, {1: 1}))
