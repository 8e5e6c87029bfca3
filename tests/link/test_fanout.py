"""Fanout: one setpoint to each of several real UDP links at once, as the loop sends them."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.link import Fanout, Link
from gcs.transport import FrameDirection, MavutilTransport
from gcs.wire import SETPOINT_MESSAGE, FrameDecoder, MavlinkEncoder, MavMessage
from gcs.wire._setpoints import MASK_ACCEL_XY_POS_Z, packed_setpoints

N = 3


@pytest.fixture
def fleet() -> Iterator[tuple[list[Link], list[socket.socket]]]:
    """Three links (vehicles 1-3) on udpin sharing one send lock, as a LinkManager opens
    them, each with a plain UDP socket playing the vehicle; every link has heard its vehicle."""
    lock = threading.Lock()
    links, socks = [], []
    for sysid in range(1, N + 1):
        transport = MavutilTransport("udpin:127.0.0.1:0")
        link = Link(sysid, transport, gcs_heartbeat_period_s=0.0, timesync_period_s=0.0,
                    send_lock=lock).start()
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.bind(("127.0.0.1", 0))
        sock.settimeout(2.0)
        vehicle = MavlinkEncoder(system_id=sysid, component_id=1)
        address = transport.local_address
        assert address is not None
        sock.sendto(vehicle.encode(vehicle.mav.heartbeat_encode(
            v20.MAV_TYPE_QUADROTOR, v20.MAV_AUTOPILOT_GENERIC, 0, 0, 0)), address)
        links.append(link)
        socks.append(sock)
    for link in links:
        link.wait_for(lambda t: t.heartbeat is not None, timeout_s=3.0, what="heartbeat")
    yield links, socks
    for link, sock in zip(links, socks, strict=True):
        link.close()
        sock.close()


def setpoints(tick: int) -> np.ndarray:
    """Tick ``tick``'s packed setpoints for vehicles 1-3: afx encodes (tick, vehicle)."""
    return packed_setpoints(
        target_system=np.arange(1, N + 1), target_component=np.ones(N, int),
        time_boot_ms=np.full(N, tick), accel_xy_ned=np.column_stack(
            [tick + np.arange(1, N + 1) / 10, np.zeros(N)]),
        vertical=np.full(N, -1.5), kind=np.full(N, MASK_ACCEL_XY_POS_Z))


def received(sock: socket.socket, count: int,
             stop: threading.Event | None = None) -> list[MavMessage]:
    """Messages from ``sock`` until ``count`` arrived (or, with ``stop``, it is set and the
    socket is quiet)."""
    decoder = FrameDecoder(datagram=True)
    out: list[MavMessage] = []
    sock.settimeout(0.1 if stop is not None else 2.0)
    while len(out) < count:
        try:
            data, _ = sock.recvfrom(2048)
        except TimeoutError:
            if stop is None:
                raise
            if stop.is_set():
                break
            continue
        out += decoder.feed(data)
    return out


def test_each_vehicle_gets_its_row_in_unbroken_sequence_with_other_frames_between(
        fleet: tuple[list[Link], list[socket.socket]]) -> None:
    links, socks = fleet
    fanout = Fanout(links)
    stop = threading.Event()
    others = [0]

    def chatter() -> None:  # another thread sends on vehicle 2's link meanwhile
        while not stop.is_set():
            links[1].send_message(links[1].mav.heartbeat_encode(
                v20.MAV_TYPE_GCS, v20.MAV_AUTOPILOT_INVALID, 0, 0, 0))
            others[0] += 1
            time.sleep(0.0005)

    inbox: list[list[MavMessage]] = [[] for _ in socks]
    readers = [threading.Thread(target=lambda s=sock, box=box: box.extend(
        received(s, 100 + (0 if s is not socks[1] else 10**6), stop=stop)))
        for sock, box in zip(socks, inbox, strict=True)]
    thread = threading.Thread(target=chatter)
    for th in [*readers, thread]:  # read as it comes: a socket buffer holds ~250 datagrams
        th.start()
    try:
        for tick in range(100):
            assert fanout.send(setpoints(tick), SETPOINT_MESSAGE.crc_extra) == {}
            time.sleep(0.001)
    finally:
        time.sleep(0.2)
        stop.set()
        for th in [thread, *readers]:
            th.join()
    for i, msgs in enumerate(inbox):
        assert len(msgs) == 100 + (others[0] if i == 1 else 0), f"vehicle {i + 1}"
        seqs = [m.get_seq() for m in msgs]
        assert seqs == [(seqs[0] + k) % 256 for k in range(len(seqs))], f"vehicle {i + 1}"
        sp = [m for m in msgs if m.get_type() == "SET_POSITION_TARGET_LOCAL_NED"]
        assert [m.afx for m in sp] == pytest.approx([t + (i + 1) / 10 for t in range(100)])
        assert {(m.target_system, m.get_srcSystem(), m.z) for m in sp} == {(i + 1, 245, -1.5)}
    assert others[0] > 10


def test_rows_left_out_are_not_numbered_and_a_closed_link_is_reported(
        fleet: tuple[list[Link], list[socket.socket]]) -> None:
    links, socks = fleet
    fanout = Fanout(links)
    seen: list[tuple[FrameDirection, bytes]] = []
    links[0].add_frame_listener(lambda d, frame: seen.append((d, frame)))
    assert fanout.send(setpoints(0), SETPOINT_MESSAGE.crc_extra, only=[0, 2]) == {}
    assert fanout.send(setpoints(1), SETPOINT_MESSAGE.crc_extra) == {}
    links[2].close()
    failed = fanout.send(setpoints(2), SETPOINT_MESSAGE.crc_extra)
    assert list(failed) == [2] and str(failed[2]) == "vehicle 3: link is closed"
    first = received(socks[0], 3)
    assert [m.get_seq() for m in first] == [0, 1, 2]
    assert [frame for d, frame in seen if d is FrameDirection.OUT] == \
        [bytes(m.get_msgbuf()) for m in first]
    (only,) = received(socks[1], 1)  # left out of the first round: its first frame is seq 0
    assert (only.get_seq(), only.afx) == (0, pytest.approx(1.2))
    for wrong in ([0, 0], [1, 3], [-1]):  # a caller's mistake, before anything is numbered
        with pytest.raises(ValueError, match=r"only: rows must be distinct, in 0\.\.2"):
            fanout.send(setpoints(3), SETPOINT_MESSAGE.crc_extra, only=wrong)
    assert links[0]._encoder.seq == 3
