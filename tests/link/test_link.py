"""One Link over real UDP: telemetry, filtering by system id, noise, loss, RTT, threads."""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Iterator

import pytest
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.link import Link
from gcs.link._health import SequenceTracker
from gcs.transport import FrameDirection, MavutilTransport
from gcs.wire import FrameDecoder, MavlinkEncoder, MavMessage, Severity
from tests.support.links import Rig, heartbeat, make_rig


@pytest.fixture
def rig() -> Iterator[Rig]:
    r = make_rig()
    yield r
    r.link.close()
    r.sock.close()


def test_latest_telemetry_of_every_kind(rig: Rig) -> None:
    mav = rig.vehicle.mav
    half = math.sqrt(0.5)
    rig.send(
        heartbeat(rig, armed=True, custom_mode=4),
        rig.encode(mav.local_position_ned_encode(2500, 1.0, 2.0, -3.0, 0.5, -0.5, 0.1)),
        rig.encode(mav.attitude_quaternion_encode(2500, half, 0.0, 0.0, half, 0.0, 0.1, 0.2)),
        rig.encode(mav.highres_imu_encode(2_500_000, 0.1, 0.2, -9.8, 0.01, 0.02, 0.03,
                                          0, 0, 0, 0, 0, 0, 0, 0)),
        rig.encode(mav.sys_status_encode(7, 7, 7, 250, 12300, 450, 80, 10, 0, 0, 0, 0, 0)),
        rig.encode(mav.statustext_encode(v20.MAV_SEVERITY_WARNING, b"rope slack")),
    )
    t = rig.wait(lambda t: t.status_texts != () and t.status is not None
                 and t.imu is not None and t.attitude is not None, "all telemetry")
    assert t.heartbeat is not None and t.heartbeat.armed and t.heartbeat.custom_mode == 4
    assert t.heartbeat.autopilot == v20.MAV_AUTOPILOT_GENERIC
    assert t.position is not None
    assert t.position.p_ned == pytest.approx((1.0, 2.0, -3.0))
    assert t.position.v_ned == pytest.approx((0.5, -0.5, 0.1))
    assert t.position.time_boot_s == pytest.approx(2.5)
    assert t.attitude is not None
    assert t.attitude.rpy == pytest.approx((0.0, 0.0, math.pi / 2), abs=1e-6)
    assert t.attitude.rates_body == pytest.approx((0.0, 0.1, 0.2))
    assert t.imu is not None and t.imu.accel_body == pytest.approx((0.1, 0.2, -9.8))
    assert t.status is not None
    assert (t.status.battery_voltage_v, t.status.battery_current_a) == pytest.approx((12.3, 4.5))
    assert t.status.battery_remaining_pct == 80 and t.status.sensors_healthy
    assert [(s.severity, s.text) for s in t.status_texts] == [(Severity.WARNING, "rope slack")]


def test_attitude_euler_fills_quaternion(rig: Rig) -> None:
    rig.send(rig.encode(rig.vehicle.mav.attitude_encode(10, 0.1, -0.2, 0.3, 0, 0, 0)))
    t = rig.wait(lambda t: t.attitude is not None, "attitude")
    assert t.attitude is not None
    w, x, y, z = t.attitude.q_wxyz
    assert w * w + x * x + y * y + z * z == pytest.approx(1.0)
    # Round trip through the quaternion form.
    rig.send(rig.encode(rig.vehicle.mav.attitude_quaternion_encode(11, w, x, y, z, 0, 0, 0)))
    t = rig.wait(lambda t: t.attitude is not None and t.attitude.time_boot_s > 0.0105,
                 "quaternion")
    assert t.attitude is not None and t.attitude.rpy == pytest.approx((0.1, -0.2, 0.3))


def test_telemetry_with_impossible_values_is_refused_and_counted(rig: Rig) -> None:
    """An ATTITUDE with infinite angles printed tracebacks; now it is refused, counted in the
    link's health (the page's "refused" column), and the good telemetry goes on."""
    inf = float("inf")
    rig.send(rig.encode(rig.vehicle.mav.attitude_encode(10, inf, 0.0, inf, 0, 0, 0)))
    rig.until(lambda: rig.link.health.refused_values == 1, "1 refused")
    assert rig.link.telemetry.attitude is None and rig.link.health.refused == 1
    rig.send(rig.encode(rig.vehicle.mav.attitude_encode(11, 0.1, 0.0, 0.2, 0, 0, 0)))
    t = rig.wait(lambda t: t.attitude is not None, "attitude")
    assert t.attitude is not None and t.attitude.rpy == pytest.approx((0.1, 0.0, 0.2))


def test_frames_from_other_systems_are_counted_and_ignored(rig: Rig) -> None:
    stranger = MavlinkEncoder(system_id=7, component_id=1)
    rig.send(*[stranger.encode(stranger.mav.local_position_ned_encode(0, 9, 9, 9, 0, 0, 0))
               for _ in range(5)])
    rig.send(rig.encode(rig.vehicle.mav.local_position_ned_encode(0, 1, 1, 1, 0, 0, 0)))
    t = rig.wait(lambda t: t.position is not None, "own position")
    assert t.position is not None and t.position.p_ned == (1.0, 1.0, 1.0)
    rig.until(lambda: rig.link.health.refused_wrong_system == 5, "5 refused")
    health = rig.link.health
    assert health.foreign_systems == (7,) and health.frames_received == 1


def test_noise_truncation_and_corruption_are_dropped_without_harm(rig: Rig) -> None:
    rng_bytes = os.urandom  # any bytes at all must be survivable
    frame = rig.encode(rig.vehicle.mav.local_position_ned_encode(0, 4, 5, 6, 0, 0, 0))
    corrupted = bytearray(frame)
    corrupted[14] ^= 0xFF
    rig.send(rng_bytes(500), b"\xfd" + rng_bytes(300), frame[:-4], bytes(corrupted),
             b"\xfd\x09", b"")
    rig.send(frame)
    t = rig.wait(lambda t: t.position is not None, "the good frame")
    assert t.position is not None and t.position.p_ned == (4.0, 5.0, 6.0)
    health = rig.link.health
    assert health.refused_bad_crc >= 1 and health.truncated >= 1 and health.garbage_bytes > 0
    assert health.frames_received == 1


def test_packet_loss_from_sequence_numbers(rig: Rig) -> None:
    frames = [heartbeat(rig) for _ in range(300)]
    kept = [f for i, f in enumerate(frames) if i % 3 != 1]  # lose every third
    rig.send(*kept)
    rig.until(lambda: rig.link.health.frames_received == len(kept), "all kept frames")
    health = rig.link.health
    assert health.packets_lost == 100
    assert health.loss_ratio == pytest.approx(100 / 300)


def test_reordered_frames_are_not_counted_lost(rig: Rig) -> None:
    """A radio (or a sender's two threads) swapping two frames lost nothing: the late one
    read as a wrap of the 8-bit number was 255 frames lost, a link that lost none."""
    frames = [heartbeat(rig) for _ in range(300)]  # the number wraps past 255
    swapped = list(frames)
    for i in (10, 100, 254):
        swapped[i], swapped[i + 1] = swapped[i + 1], swapped[i]
    for start in range(0, len(swapped), 50):  # within a socket's buffer (heartbeats, 1 kB
        rig.send(*swapped[start:start + 50])  # each in the kernel's count)
        sent = min(start + 50, len(frames))
        rig.until(lambda n=sent: rig.link.health.frames_received == n, f"{sent} frames")
    assert rig.link.health.packets_lost == 0


@pytest.mark.parametrize(("seqs", "lost"), [
    ([1, 2, 4, 5], 1),                 # one missing
    ([1, 2, 4, 3, 5], 0),              # late, counted back
    ([250, 252, 255, 0, 251, 1], 2),   # gaps up to the wrap; one of them late
    ([1, 2, 2, 3], 0),                 # a duplicate
    ([3, 3, 1, 1], 0),                 # a duplicate of a late frame never missed
    ([200, 201, 150, 151, 202, 205], 2),  # the sender started again: no loss read into it
    ([5, 9, 7, 7, 6], 1),              # a late frame counted back once, not twice
])
def test_sequence_tracker_counts_what_never_came(seqs: list[int], lost: int) -> None:
    tracker = SequenceTracker()
    for seq in seqs:
        tracker.update(1, 1, seq)
    tracker.update(2, 1, 0)  # another stream's numbers are its own
    tracker.update(2, 1, 10)
    assert tracker.lost == lost + 9


def test_heartbeat_age_and_alive(rig: Rig) -> None:
    assert rig.link.health.heartbeat_age_s is None and not rig.link.health.alive
    rig.send(heartbeat(rig))
    rig.wait(lambda t: t.heartbeat is not None, "heartbeat")
    health = rig.link.health
    assert health.alive and health.heartbeat_age_s is not None and health.heartbeat_age_s < 1.0


def test_heartbeat_age_follows_the_link_clock() -> None:
    now = [100.0]
    r = make_rig(clock=lambda: now[0], heartbeat_timeout_s=3.0)
    try:
        r.send(heartbeat(r))
        r.wait(lambda t: t.heartbeat is not None, "heartbeat")
        now[0] = 102.0
        assert r.link.health.heartbeat_age_s == pytest.approx(2.0) and r.link.health.alive
        now[0] = 103.5
        assert not r.link.health.alive
    finally:
        r.link.close()
        r.sock.close()


def receive_from_link(rig: Rig, kind: str, timeout_s: float = 3.0) -> MavMessage:
    decoder = FrameDecoder(datagram=True)
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        data, _ = rig.sock.recvfrom(2048)
        for msg in decoder.feed(data):
            if msg.get_type() == kind:
                return msg
    raise AssertionError(f"no {kind} from the link")


def test_gcs_heartbeat_has_its_own_ids() -> None:
    r = make_rig(gcs_heartbeat_period_s=0.05)
    try:
        r.send(heartbeat(r))  # udpin replies to whoever spoke
        msg = receive_from_link(r, "HEARTBEAT")
    finally:
        r.link.close()
        r.sock.close()
    assert (msg.get_srcSystem(), msg.get_srcComponent()) == (245, 190)
    assert msg.type == v20.MAV_TYPE_GCS and msg.get_msgbuf()[0] == 0xFD


def test_rtt_from_timesync_and_answer_to_vehicle_probe() -> None:
    r = make_rig(timesync_period_s=0.05)
    try:
        r.send(heartbeat(r))
        probe = receive_from_link(r, "TIMESYNC")
        assert probe.tc1 == 0
        r.send(r.encode(r.vehicle.mav.timesync_encode(123, probe.ts1)))
        r.until(lambda: r.link.health.rtt_s is not None, "rtt")
        rtt = r.link.health.rtt_s
        assert rtt is not None and 0.0 < rtt < 1.0

        r.send(r.encode(r.vehicle.mav.timesync_encode(0, 987654321)))
        decoder = FrameDecoder(datagram=True)
        deadline = time.monotonic() + 3.0
        answer = None
        while answer is None and time.monotonic() < deadline:
            data, _ = r.sock.recvfrom(2048)
            answer = next((m for m in decoder.feed(data) if m.get_type() == "TIMESYNC"
                           and m.tc1 != 0), None)
        assert answer is not None and answer.ts1 == 987654321
    finally:
        r.link.close()
        r.sock.close()


def test_setpoints_reach_the_vehicle_as_sent(rig: Rig) -> None:
    rig.send(heartbeat(rig))
    rig.wait(lambda t: t.heartbeat is not None, "heartbeat")
    rig.link.send_setpoint(accel_xy_ned=(0.4, -0.3), z_ned=-1.1)
    msg = receive_from_link(rig, "SET_POSITION_TARGET_LOCAL_NED")
    assert (msg.target_system, msg.target_component, msg.type_mask) == (1, 1, 3387)
    assert (msg.afx, msg.afy, msg.z) == pytest.approx((0.4, -0.3, -1.1))


def test_listeners_see_messages_and_frames_both_ways(rig: Rig) -> None:
    messages: list[str] = []
    frames: list[tuple[FrameDirection, int]] = []
    rig.link.add_message_listener(lambda m: messages.append(m.get_type()))
    rig.link.add_frame_listener(lambda d, f: frames.append((d, f[5])))
    rig.send(heartbeat(rig))
    rig.wait(lambda t: t.heartbeat is not None, "heartbeat")
    rig.link.send_setpoint(accel_xy_ned=(0.0, 0.0), z_ned=-1.0)
    rig.until(lambda: len(frames) == 2, "two frames")
    assert messages == ["HEARTBEAT"]
    assert sorted(frames, key=lambda x: x[0].value) == [(FrameDirection.IN, 1),
                                                        (FrameDirection.OUT, 245)]


def test_snapshots_stay_consistent_while_frames_stream_in(rig: Rig) -> None:
    """The 4 Hz loop reads while the transport thread writes: each record is whole."""
    n = 1500
    problems: list[str] = []
    done = threading.Event()

    def reader() -> None:
        last = -1.0
        while not done.is_set():
            t = rig.link.telemetry
            h = rig.link.health
            if t.position is not None:
                x, vx = t.position.p_ned[0], t.position.v_ned[0]
                if x != vx:
                    problems.append(f"torn record {x} {vx}")
                if x < last:
                    problems.append(f"went back {last} -> {x}")
                last = x
            if h.frames_received < 0:
                problems.append("bad health")
            time.sleep(0)  # yield the GIL, as a real loop would

    readers = [threading.Thread(target=reader) for _ in range(2)]
    for th in readers:
        th.start()
    mav = rig.vehicle.mav

    def position(i: int) -> bytes:
        return rig.encode(mav.local_position_ned_encode(i, float(i), 0, 0, float(i), 0, 0))

    for i in range(n):
        rig.send(position(i))
        if i % 50 == 0:
            time.sleep(0.001)  # UDP may still drop some on a loaded machine: that is fine
    try:
        rig.until(lambda: rig.link.health.frames_received > n // 2, "most frames")
        for _ in range(50):  # the last value must arrive eventually
            rig.send(position(n))
            t = rig.link.telemetry
            if t.position is not None and t.position.p_ned[0] == n:
                break
            time.sleep(0.02)
        t = rig.link.telemetry
        assert t.position is not None and t.position.p_ned[0] == n
    finally:
        done.set()
        for th in readers:
            th.join()
    assert problems == []


def test_send_after_close_is_an_error(rig: Rig) -> None:
    rig.link.close()
    with pytest.raises(RuntimeError, match="vehicle 1: link is closed"):
        rig.link.send_setpoint(accel_xy_ned=(0, 0), z_ned=-1)


def test_link_refuses_its_own_system_id() -> None:
    transport = MavutilTransport("udpin:127.0.0.1:0")
    try:
        with pytest.raises(ValueError, match="equals the GCS's own system id"):
            Link(245, transport)
    finally:
        transport.close()
