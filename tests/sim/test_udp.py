"""The sim host's plain MAVLink UDP ports, as MAVProxy or QGroundControl would use them.

A pymavlink ``mavutil`` connection, exactly as a user script or MAVProxy opens
it, talks to ``python -m sim --udp``: the vehicles announce themselves to a
ground-station port (QGC's ``udpin`` way), and one vehicle answers a client
that connects to its own port (``udpout``).
"""

from __future__ import annotations

import time
import uuid
from collections.abc import Iterator

import pytest
from pymavlink import mavutil

from gcs.app import SimProcess, free_tcp_port
from gcs.app._simprocess import SimStartError
from gcs.testing import signed_connection
from gcs.wire import SIM_PX4_MODES, SimMode, mavlink
from tests.support.paths import ROOT
from tests.support.ports import free_udp_ports

CONFIG = ROOT / "configs" / "bebop_square.yaml"
GCS_SYSID = 245


RUNNING: list[SimProcess] = []
"""The module's simulator (for its stderr)."""


@pytest.fixture(scope="module")
def udp_sim() -> Iterator[tuple[int, int]]:
    """A sim host with UDP ports; yields (vehicle base port, ground-station port)."""
    for _ in range(3):
        base, gcs_port = free_udp_ports(4), free_udp_ports(1)
        try:
            sim = SimProcess(CONFIG, endpoint=f"tcp/127.0.0.1:{free_tcp_port()}",
                             extra=("--fleet", f"simudp-{uuid.uuid4().hex[:8]}", "--udp",
                                    "--udp-base-port", str(base), "--udp-gcs-port",
                                    str(gcs_port)), ready_timeout=90.0)
        except SimStartError as exc:
            if "cannot" not in str(exc):  # a port taken meanwhile: try others
                raise
            continue
        assert f"udp 1=127.0.0.1:{base} 2=127.0.0.1:{base + 1}" in sim.ready_line
        assert f"-> gcs 127.0.0.1:{gcs_port}" in sim.ready_line
        RUNNING[:] = [sim]
        try:
            yield base, gcs_port
        finally:
            sim.close()
        return
    pytest.fail("no free ports for the UDP sim")


def test_vehicles_announce_themselves_to_the_ground_station_port(
        udp_sim: tuple[int, int]) -> None:
    _, gcs_port = udp_sim
    conn = mavutil.mavlink_connection(f"udpin:127.0.0.1:{gcs_port}",
                                      source_system=GCS_SYSID, source_component=190)
    try:
        seen: set[int] = set()
        deadline = time.monotonic() + 5.0
        while seen != {1, 2, 3, 4} and time.monotonic() < deadline:
            msg = conn.recv_match(type="HEARTBEAT", blocking=True, timeout=0.5)
            if msg is not None:
                assert msg.autopilot == mavlink.MAV_AUTOPILOT_PX4
                seen.add(msg.get_srcSystem())
        assert seen == {1, 2, 3, 4}
    finally:
        conn.close()


def test_a_client_on_a_vehicle_port_gets_heartbeats_and_command_acks(
        udp_sim: tuple[int, int]) -> None:
    base, _ = udp_sim
    conn = signed_connection(f"udpout:127.0.0.1:{base + 1}",  # vehicle 2
                             source_system=GCS_SYSID, source_component=190)
    try:
        deadline = time.monotonic() + 5.0
        heartbeat = None
        while heartbeat is None and time.monotonic() < deadline:
            conn.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            heartbeat = conn.recv_match(type="HEARTBEAT", blocking=True, timeout=0.5)
        assert heartbeat is not None, "no HEARTBEAT from the vehicle's UDP port"
        assert heartbeat.get_srcSystem() == 2
        assert heartbeat.custom_mode == SIM_PX4_MODES[SimMode.DISARMED]
        conn.mav.command_long_send(2, 1, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0,
                                   1, 0, 0, 0, 0, 0, 0)
        ack = conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=3.0)
        assert ack is not None and ack.get_srcSystem() == 2
        assert (ack.command, ack.result) == (mavlink.MAV_CMD_COMPONENT_ARM_DISARM,
                                             mavlink.MAV_RESULT_ACCEPTED)
        assert ack.target_system == GCS_SYSID
        armed = conn.recv_match(type="HEARTBEAT", blocking=True, timeout=3.0)
        assert armed is not None and armed.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED
    finally:
        conn.close()


def _heartbeat_of(conn: object, sysid: int, timeout: float = 3.0) -> object:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        conn.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID,  # type: ignore[attr-defined]
                                0, 0, 0)
        msg = conn.recv_match(type="HEARTBEAT", blocking=True, timeout=0.5)  # type: ignore[attr-defined]
        if msg is not None and msg.get_srcSystem() == sysid:
            return msg
    raise AssertionError(f"no HEARTBEAT from vehicle {sysid}")


def test_a_strangers_unsigned_arm_is_refused_and_the_vehicle_stays_disarmed(
        udp_sim: tuple[int, int]) -> None:
    base, _ = udp_sim
    stranger = mavutil.mavlink_connection(f"udpout:127.0.0.1:{base + 2}",  # vehicle 3
                                          source_system=77, source_component=190)
    owner = signed_connection(f"udpout:127.0.0.1:{base + 2}")
    try:
        for _ in range(5):
            stranger.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID,
                                        0, 0, 0)
            stranger.mav.command_long_send(3, 1, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0,
                                           1, 0, 0, 0, 0, 0, 0)
            ack = stranger.recv_match(type="COMMAND_ACK", blocking=True, timeout=0.3)
            assert ack is None, f"the stranger's ARM was answered: {ack}"
        heartbeat = _heartbeat_of(owner, 3)
        assert not heartbeat.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED  # type: ignore[attr-defined]
    finally:
        stranger.close()
        owner.close()
    deadline = time.monotonic() + 20.0  # and the simulator says so, once
    while time.monotonic() < deadline and not any(
            "vehicle 3:" in line and "not signed with the team key" in line
            for line in RUNNING[0].stderr_tail):
        time.sleep(0.1)
    said = [line for line in RUNNING[0].stderr_tail if "not signed with the team key" in line]
    assert said and said[0].startswith("sim: ignored MAVLink frame: vehicle 3: "), \
        RUNNING[0].stderr_tail


def test_a_replayed_signed_command_is_refused(udp_sim: tuple[int, int]) -> None:
    base, _ = udp_sim
    owner = signed_connection(f"udpout:127.0.0.1:{base + 3}")  # vehicle 4
    try:
        _heartbeat_of(owner, 4)
        arm = owner.mav.command_long_encode(4, 1, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0,
                                            1, 0, 0, 0, 0, 0, 0)
        frame = arm.pack(owner.mav)  # signed, as sent
        owner.write(frame)
        ack = owner.recv_match(type="COMMAND_ACK", blocking=True, timeout=3.0)
        assert ack is not None and ack.result == mavlink.MAV_RESULT_ACCEPTED
        owner.mav.command_long_send(4, 1, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0,
                                    0, 0, 0, 0, 0, 0, 0)
        ack = owner.recv_match(type="COMMAND_ACK", blocking=True, timeout=3.0)
        assert ack is not None and ack.result == mavlink.MAV_RESULT_ACCEPTED
        owner.write(frame)  # the same signed ARM again: a replay
        assert owner.recv_match(type="COMMAND_ACK", blocking=True, timeout=1.0) is None
        heartbeat = _heartbeat_of(owner, 4)
        assert not heartbeat.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED  # type: ignore[attr-defined]
    finally:
        owner.close()


def test_insecure_is_explicit_and_said() -> None:
    """``--insecure`` turns signing off, and the simulator says so in its ready line: then
    anyone's ARM is obeyed, which is what the flag means."""
    base = free_udp_ports(4)
    with SimProcess(CONFIG, endpoint=f"tcp/127.0.0.1:{free_tcp_port()}", signing=False,
                    extra=("--fleet", f"simudp-{uuid.uuid4().hex[:8]}", "--udp",
                           "--udp-base-port", str(base), "--udp-gcs-port", "0"),
                    ready_timeout=90.0) as sim:
        assert "UNSIGNED (--insecure" in sim.ready_line
        anyone = mavutil.mavlink_connection(f"udpout:127.0.0.1:{base}", source_system=77,
                                            source_component=190)
        try:
            located = None  # a vehicle without a position refuses to arm, as PX4 does
            deadline = time.monotonic() + 10.0
            while located is None and time.monotonic() < deadline:
                anyone.mav.heartbeat_send(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID,
                                          0, 0, 0)
                located = anyone.recv_match(type="LOCAL_POSITION_NED", blocking=True,
                                            timeout=0.5)
            assert located is not None, "vehicle 1 never reported a position"
            anyone.mav.command_long_send(1, 1, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0,
                                         1, 0, 0, 0, 0, 0, 0)
            ack = anyone.recv_match(type="COMMAND_ACK", blocking=True, timeout=5.0)
            assert ack is not None and ack.result == mavlink.MAV_RESULT_ACCEPTED
        finally:
            anyone.close()
