"""The simulated vehicle's MAVLink endpoint, driven with real frames against real physics.

No network: a GCS-side encoder writes the bytes a GCS would send, the endpoint
acts on a real World and Autopilot, and its frames are decoded back with the
GCS's own decoder. Everything the GCS relies on is checked from the bytes.
"""

from __future__ import annotations

import itertools
import math
import threading
from collections import Counter
from dataclasses import dataclass, field

import numpy as np
import pytest

from gcs.wire import (
    CUSTOM_MODE_ENABLED,
    SAFETY_ARMED,
    SIM_PX4_MODES,
    FrameDecoder,
    MavlinkEncoder,
    MavMessage,
    Px4MainMode,
    SigningKey,
    SimMode,
    mavlink,
    px4_base_mode,
)
from gcs.wire._setpoints import MASK_ACCEL, MASK_ACCEL_XY_POS_Z, accel_setpoint_message
from sim import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    build_team,
    load_world_config,
    paper_square,
)
from sim._world import World
from vehicles import Autopilot, load_airframe, load_autopilot_config
from vehicles._battery import Battery, BatteryConfig
from vehicles._streams import StreamSchedule, TelemetryMessage
from vehicles.endpoint import VehicleEndpoint

SYSID = 7
GCS = 245
GCS_COMP = 190
CHUNK = 1.0 / 128.0
ARM = mavlink.MAV_CMD_COMPONENT_ARM_DISARM
TAKEOFF = mavlink.MAV_CMD_NAV_TAKEOFF
SET_MODE = mavlink.MAV_CMD_DO_SET_MODE
INTERVAL = mavlink.MAV_CMD_SET_MESSAGE_INTERVAL
ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
DENIED = mavlink.MAV_RESULT_DENIED
OFFBOARD = Px4MainMode.OFFBOARD
"""DO_SET_MODE param2 of OFFBOARD: the vehicles take PX4's modes."""


@dataclass
class Bench:
    """One vehicle of the paper's square behind its endpoint, and a GCS that talks to it."""

    world: World
    autopilot: Autopilot
    endpoint: VehicleEndpoint
    sent: list[bytes]
    gcs: MavlinkEncoder = field(default_factory=lambda: MavlinkEncoder(
        system_id=GCS, component_id=GCS_COMP))
    decoder: FrameDecoder = field(default_factory=lambda: FrameDecoder(datagram=True))

    def run(self, seconds: float) -> None:
        for _ in range(round(seconds / CHUNK)):
            self.world.run(self.autopilot, CHUNK)
            self.endpoint.update(self.world.t)

    def send(self, msg: MavMessage) -> None:
        self.endpoint.receive(self.gcs.encode(msg), self.world.t)

    def command(self, command: int, *params: float, target: int = SYSID,
                component: int = 1) -> None:
        p = [float(x) for x in params] + [0.0] * (7 - len(params))
        self.send(self.gcs.mav.command_long_encode(target, component, command, 0, *p))

    def setpoint(self, accel_xy: tuple[float, float], z: float | None = None, *,
                 az: float | None = None, target: int = SYSID) -> None:
        self.send(accel_setpoint_message(target_system=target, target_component=1,
                                         time_boot_ms=0, accel_xy_ned=accel_xy, z_ned=z,
                                         az_ned=az))

    def raw_setpoint(self, *, frame: int = mavlink.MAV_FRAME_LOCAL_NED,
                     mask: int = MASK_ACCEL_XY_POS_Z, afx: float = 0.0, z: float = -1.0) -> None:
        self.send(self.gcs.mav.set_position_target_local_ned_encode(
            0, SYSID, 1, frame, mask, 0.0, 0.0, z, 0.0, 0.0, 0.0, afx, 0.0, 0.0, 0.0, 0.0))

    def received(self) -> list[MavMessage]:
        """Every message the endpoint sent since the last call, decoded by the GCS's decoder."""
        out = [m for frame in self.sent for m in self.decoder.feed(frame)]
        self.sent.clear()
        return out


def bench(*, signing_key: SigningKey | None = None, battery: Battery | None = None) -> Bench:
    world, autopilot = build_team(
        paper_square(), payload_mass=0.4, rng=np.random.default_rng(5),
        airframe=load_airframe(DEFAULT_AIRFRAME),
        world_config=load_world_config(DEFAULT_WORLD_CONFIG),
        autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    sent: list[bytes] = []
    endpoint = VehicleEndpoint(autopilot, 0, sysid=SYSID, measurements=world.measurements(),
                               send=sent.append, signing_key=signing_key, battery=battery)
    return Bench(world, autopilot, endpoint, sent)


def of_type(messages: list[MavMessage], kind: str) -> list[MavMessage]:
    return [m for m in messages if m.get_type() == kind]


def acks(messages: list[MavMessage]) -> list[tuple[int, int]]:
    return [(m.command, m.result) for m in of_type(messages, "COMMAND_ACK")]


def texts(messages: list[MavMessage]) -> list[str]:
    return [m.text for m in of_type(messages, "STATUSTEXT")]


def take_off(b: Bench, climb: float = 1.0) -> None:
    b.run(0.05)
    b.command(ARM, 1)
    b.command(TAKEOFF, 0, 0, 0, 0, 0, 0, climb)
    b.run(climb / 0.5 + 1.5)
    assert b.autopilot.mode(0) is SimMode.HOLD


def test_heartbeat_and_telemetry_stream_at_the_default_rates_in_sim_time() -> None:
    b = bench()
    b.run(2.0)
    got = b.received()
    counts = Counter(m.get_type() for m in got)
    assert all(m.get_srcSystem() == SYSID and m.get_srcComponent() == 1 for m in got)
    assert counts["HEARTBEAT"] == 2  # 1 Hz, starting at once
    assert counts["LOCAL_POSITION_NED"] == pytest.approx(100, abs=2)  # 50 Hz
    assert counts["ATTITUDE"] == pytest.approx(100, abs=2)
    assert counts["ATTITUDE_QUATERNION"] == pytest.approx(20, abs=1)
    assert counts["HIGHRES_IMU"] == pytest.approx(20, abs=1)
    assert counts["SYS_STATUS"] == pytest.approx(4, abs=1)
    assert counts["GPS_RAW_INT"] == pytest.approx(10, abs=1)  # 5 Hz
    assert counts["GLOBAL_POSITION_INT"] == pytest.approx(20, abs=1)  # 10 Hz
    hb = of_type(got, "HEARTBEAT")[-1]
    assert (hb.type, hb.autopilot) == (mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_PX4)
    disarmed = SIM_PX4_MODES[SimMode.DISARMED]
    assert hb.custom_mode == disarmed and hb.base_mode == px4_base_mode(disarmed, armed=False)
    assert not hb.base_mode & SAFETY_ARMED
    assert hb.system_status == mavlink.MAV_STATE_STANDBY
    position = of_type(got, "LOCAL_POSITION_NED")[-1]
    assert position.time_boot_ms == pytest.approx(2000, abs=20)  # sim time, ms
    assert (position.x, position.y) == pytest.approx((0.5, 0.5), abs=0.02)  # its start corner
    imu = of_type(got, "HIGHRES_IMU")[-1]
    assert imu.zacc == pytest.approx(-9.81, abs=1.5) and imu.time_usec == pytest.approx(2e6, 2e4)
    attitude = of_type(got, "ATTITUDE")[-1]
    assert abs(attitude.roll) < 0.05 and abs(attitude.yaw) < 0.05
    status = of_type(got, "SYS_STATUS")[-1]
    assert 12.0 < status.voltage_battery / 1000 <= 12.6 and status.battery_remaining == 100


def test_set_message_interval_changes_rates_and_refuses_unknown_messages() -> None:
    b = bench()
    b.run(0.05)
    b.command(INTERVAL, mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 100_000)  # 10 Hz
    b.command(INTERVAL, mavlink.MAVLINK_MSG_ID_HIGHRES_IMU, -1)  # stop
    b.command(INTERVAL, mavlink.MAVLINK_MSG_ID_SYS_STATUS, 0)  # default (2 Hz)
    b.command(INTERVAL, mavlink.MAVLINK_MSG_ID_VFR_HUD, 100_000)  # not sent here
    b.command(INTERVAL, mavlink.MAVLINK_MSG_ID_ATTITUDE, -5)  # not a valid interval
    first = b.received()
    assert acks(first) == [(INTERVAL, ACCEPTED)] * 3 + [(INTERVAL, DENIED)] * 2
    assert texts(first) == ["interval: not a message this vehicle sends",
                            "interval: interval must be -1, 0 or > 0 us"]
    b.run(2.0)
    counts = Counter(m.get_type() for m in b.received())
    assert counts["LOCAL_POSITION_NED"] == pytest.approx(20, abs=1)
    assert counts["HIGHRES_IMU"] == 0
    assert counts["SYS_STATUS"] == pytest.approx(4, abs=1)
    assert counts["ATTITUDE"] == pytest.approx(100, abs=2)  # untouched


def test_commands_are_acknowledged_with_the_result_a_real_autopilot_gives() -> None:
    b = bench()
    b.command(ARM, 1)  # before the first position sample
    b.run(0.05)
    b.command(TAKEOFF, 0, 0, 0, 0, 0, 0, 1.0)  # while disarmed
    b.command(mavlink.MAV_CMD_DO_SET_SERVO, 1, 1500)  # not supported here
    b.command(ARM, 1)
    b.command(SET_MODE, CUSTOM_MODE_ENABLED, OFFBOARD)  # no setpoint stream
    b.command(SET_MODE, CUSTOM_MODE_ENABLED, 42)  # no such mode
    b.command(TAKEOFF, 0, 0, 0, 0, 0, 0, 1.0)
    got = b.received()
    assert acks(got) == [
        (ARM, mavlink.MAV_RESULT_TEMPORARILY_REJECTED), (TAKEOFF, DENIED),
        (mavlink.MAV_CMD_DO_SET_SERVO, mavlink.MAV_RESULT_UNSUPPORTED), (ARM, ACCEPTED),
        (SET_MODE, DENIED), (SET_MODE, DENIED), (TAKEOFF, ACCEPTED)]
    assert all((m.target_system, m.target_component) == (GCS, GCS_COMP)
               for m in of_type(got, "COMMAND_ACK"))
    # Every refusal explains itself; a reason longer than one STATUSTEXT is sent in chunks.
    statustexts = of_type(got, "STATUSTEXT")
    assert "arm denied: no position measurement received yet" in texts(got)
    assert "takeoff denied: vehicle is disarmed" in texts(got)
    chunked: dict[int, list[MavMessage]] = {}
    for m in statustexts:
        if m.id != 0:
            chunked.setdefault(m.id, []).append(m)
    assert [[m.chunk_seq for m in c] for c in chunked.values()] == [[0, 1], [0, 1]]
    assert ["".join(m.text for m in c) for c in chunked.values()] == [
        "mode OFFBOARD denied: no setpoint received within the setpoint timeout",
        "set mode: PX4 mode 42.0 is not a mode of this vehicle"]
    # A mode change is reported by a HEARTBEAT at once, not at the next 1 Hz beat.
    modes = [(bool(m.base_mode & SAFETY_ARMED), m.custom_mode)
             for m in of_type(got, "HEARTBEAT")]
    assert modes[-2:] == [(True, SIM_PX4_MODES[SimMode.HOLD]),
                          (True, SIM_PX4_MODES[SimMode.TAKEOFF])]
    b.run(3.5)
    got = b.received()
    assert of_type(got, "HEARTBEAT")[-1].custom_mode == SIM_PX4_MODES[SimMode.HOLD]
    assert of_type(got, "LOCAL_POSITION_NED")[-1].z == pytest.approx(-1.0, abs=0.1)
    b.command(mavlink.MAV_CMD_NAV_LAND)
    b.command(ARM, 0)  # in flight: refused
    b.command(ARM, 0, 21196)  # forced: the kill switch
    assert acks(b.received()) == [(mavlink.MAV_CMD_NAV_LAND, ACCEPTED), (ARM, DENIED),
                                  (ARM, ACCEPTED)]
    assert b.autopilot.mode(0) is SimMode.DISARMED


def test_accepted_setpoints_are_echoed_at_once_and_flown() -> None:
    b = bench()
    take_off(b)
    b.received()
    b.setpoint((0.8, -0.4), -1.2)
    (echo,) = of_type(b.received(), "POSITION_TARGET_LOCAL_NED")
    assert (echo.type_mask, echo.coordinate_frame) == (MASK_ACCEL_XY_POS_Z,
                                                       mavlink.MAV_FRAME_LOCAL_NED)
    assert (echo.afx, echo.afy, echo.z) == pytest.approx((0.8, -0.4, -1.2))
    assert echo.time_boot_ms == pytest.approx(b.world.t * 1000, abs=1)
    b.command(SET_MODE, CUSTOM_MODE_ENABLED, OFFBOARD)
    assert acks(b.received()) == [(SET_MODE, ACCEPTED)]
    x0 = b.autopilot.p_ned[0, 0]
    for _ in range(8):  # 4 Hz for 2 s
        b.setpoint((0.8, 0.0), -1.0)
        b.run(0.25)
    assert b.autopilot.mode(0) is SimMode.OFFBOARD
    assert b.autopilot.p_ned[0, 0] - x0 > 0.5  # pulling the payload, so less than a t^2 / 2
    b.received()
    b.setpoint((0.0, 0.0), az=0.0)  # acceleration on all axes (the ArduPilot profile's kind)
    (echo,) = of_type(b.received(), "POSITION_TARGET_LOCAL_NED")
    assert echo.type_mask == MASK_ACCEL
    assert b.endpoint.counters().setpoints_accepted == 10
    b.run(1.0)  # the stream stops: the setpoint timeout returns the vehicle to HOLD
    assert of_type(b.received(), "HEARTBEAT")[0].custom_mode == SIM_PX4_MODES[SimMode.HOLD]


def test_refused_setpoints_are_reported_and_never_flown() -> None:
    b = bench()
    take_off(b)
    b.received()
    sp_time = b.autopilot.state.sp_time[0]
    b.raw_setpoint(mask=0b110111111000)  # position only
    b.raw_setpoint(frame=mavlink.MAV_FRAME_BODY_NED)
    b.raw_setpoint(afx=math.nan)
    b.raw_setpoint(afx=1e3)
    b.raw_setpoint(z=-500.0)
    b.raw_setpoint(mask=MASK_ACCEL, afx=math.inf)
    got = b.received()
    assert of_type(got, "POSITION_TARGET_LOCAL_NED") == []
    assert texts(got) == [
        "setpoint refused: type_mask 3576 unsupported",
        "setpoint refused: frame 8 not LOCAL_NED",
        "setpoint refused: NaN or infinite value",
        "setpoint refused: accel 1e+03 > 10 m/s^2"]  # same reason again within 1 s: counted only
    assert all(m.severity == mavlink.MAV_SEVERITY_WARNING for m in of_type(got, "STATUSTEXT"))
    assert b.autopilot.state.sp_time[0] == sp_time  # nothing reached the autopilot
    b.command(SET_MODE, CUSTOM_MODE_ENABLED, OFFBOARD)
    assert acks(b.received()) == [(SET_MODE, DENIED)]
    b.run(1.0)
    got = b.received()
    assert b.autopilot.mode(0) is SimMode.HOLD
    assert of_type(got, "SYS_STATUS")[-1].errors_count3 == 6  # every refusal counted
    assert b.endpoint.counters().setpoints_refused == 6
    b.run(0.5)
    b.raw_setpoint(z=-500.0)
    assert texts(b.received()) == ["setpoint refused: |z| 500 > 100 m"]  # a second later


def test_frames_for_other_systems_are_ignored() -> None:
    b = bench()
    b.run(0.05)
    b.received()
    b.command(ARM, 1, target=SYSID + 1)
    b.command(ARM, 1, component=50)
    b.setpoint((0.1, 0.0), -1.0, target=SYSID + 1)
    assert acks(b.received()) == [] and not b.autopilot.armed[0]
    assert b.endpoint.counters().not_for_us == 3
    b.command(ARM, 1, target=0)  # broadcast: for everyone
    assert acks(b.received()) == [(ARM, ACCEPTED)] and b.autopilot.armed[0]


def test_random_and_truncated_bytes_are_counted_and_dropped() -> None:
    b = bench()
    b.run(0.05)
    b.received()
    rng = np.random.default_rng(11)
    noise = rng.integers(0, 256, 20_000, dtype=np.uint8).tobytes()
    for start in range(0, len(noise), 200):  # datagrams of noise
        b.endpoint.receive(noise[start:start + 200], b.world.t)
    frame = b.gcs.encode(b.gcs.mav.command_long_encode(SYSID, 1, ARM, 0, 1, 0, 0, 0, 0, 0, 0))
    b.endpoint.receive(frame[:-3], b.world.t)  # truncated
    corrupt = bytearray(frame)
    corrupt[12] ^= 0xFF
    b.endpoint.receive(bytes(corrupt), b.world.t)  # bad checksum
    b.endpoint.receive(b"\xfd" * 5 + noise[:50] + frame + b"\x00\xfe\x09", b.world.t)
    stats = b.endpoint.counters().decode
    assert stats.garbage_bytes > 10_000 and stats.truncated >= 2 and stats.bad_crc >= 1
    assert acks(b.received()) == [(ARM, ACCEPTED)]  # the good frame among the junk still works
    assert b.autopilot.armed[0]
    b.run(0.5)
    status = of_type(b.received(), "SYS_STATUS")[-1]
    assert status.errors_comm == min(0xFFFF, stats.dropped) and status.errors_comm > 0
    assert status.errors_count2 == min(0xFFFF, stats.garbage_bytes)


def test_timesync_is_answered_with_the_vehicle_clock() -> None:
    b = bench()
    b.run(0.5)
    b.received()
    b.send(b.gcs.mav.timesync_encode(0, 123456789))
    b.send(b.gcs.mav.timesync_encode(5, 99))  # an answer to someone else's probe
    (reply,) = of_type(b.received(), "TIMESYNC")
    assert reply.ts1 == 123456789 and reply.tc1 == pytest.approx(b.world.t * 1e9, rel=1e-6)


def test_signed_endpoint_signs_everything_and_refuses_unsigned_frames() -> None:
    key = SigningKey(bytes(range(1, 33)))
    b = bench(signing_key=key)
    b.decoder = FrameDecoder(datagram=True, signing_key=key)
    b.run(0.05)
    assert all(frame[2] & 0x01 for frame in b.sent)  # MAVLINK_IFLAG_SIGNED
    assert of_type(b.received(), "HEARTBEAT")  # and they verify with the key
    b.command(ARM, 1)  # unsigned
    assert b.received() == [] and not b.autopilot.armed[0]
    assert b.endpoint.counters().decode.refused_unsigned == 1
    b.gcs = MavlinkEncoder(system_id=GCS, component_id=GCS_COMP, signing_key=key, link_id=3)
    b.command(ARM, 1)
    assert acks(b.received()) == [(ARM, ACCEPTED)]


def test_battery_sags_with_thrust_and_drains_with_time() -> None:
    hover = [0.4 * 9.81 / 4] * 4
    rest, loaded = Battery(), Battery()
    rest.draw([0.0] * 4, 1.0)
    loaded.draw([2 * f for f in hover], 1.0)
    assert loaded.reading().voltage_v < rest.reading().voltage_v - 0.5
    flight = Battery()
    minutes = 0
    while flight.reading().remaining > 0.0:
        flight.draw(hover, 60.0)
        minutes += 1
    assert 22 <= minutes <= 32  # Parrot quotes about 25 min for the Bebop 2
    assert 9.0 < flight.reading().voltage_v < 9.9  # empty pack (3.3 V per cell), sagging
    hovering = Battery()
    hovering.draw(hover, 1.0)
    assert 4.0 < hovering.reading().current_a < 8.0
    with pytest.raises(ValueError):
        BatteryConfig(capacity_mah=0.0)

    b = bench(battery=Battery(charge=0.1))
    b.run(0.6)
    got = b.received()
    assert of_type(got, "HEARTBEAT")[-1].system_status == mavlink.MAV_STATE_CRITICAL
    status = of_type(got, "SYS_STATUS")[-1]
    assert status.battery_remaining == 10
    assert not status.onboard_control_sensors_health & mavlink.MAV_SYS_STATUS_SENSOR_BATTERY


def test_stream_schedule_keeps_its_rate_and_never_bursts_after_a_gap() -> None:
    schedule = StreamSchedule({TelemetryMessage.LOCAL_POSITION_NED: 50.0})
    sent = [t for t in np.arange(0.0, 1.0, CHUNK)
            if TelemetryMessage.LOCAL_POSITION_NED in list(schedule.due(float(t)))]
    assert len(sent) == 50
    assert list(schedule.due(10.0)) == [TelemetryMessage.LOCAL_POSITION_NED]
    assert list(schedule.due(10.0 + CHUNK)) == []  # one message after the gap, not 450
    assert TelemetryMessage.HEARTBEAT not in list(schedule.due(20.0))  # not asked for: never
    with pytest.raises(ValueError):
        StreamSchedule({TelemetryMessage.HEARTBEAT: -1.0})


def test_echoes_from_a_receive_thread_keep_the_sequence_in_order() -> None:
    """take() echoes on its own thread while the loop sends telemetry: no reordering."""
    b = bench()
    frame = b.gcs.encode(accel_setpoint_message(
        target_system=SYSID, target_component=1, time_boot_ms=0, accel_xy_ned=(0.1, 0.0),
        z_ned=-1.0))
    stop = threading.Event()
    taken: list[object] = []

    def receiver() -> None:
        while not stop.is_set():
            taken.extend(b.endpoint.take(frame, b.world.t))

    thread = threading.Thread(target=receiver)
    thread.start()
    try:
        b.run(1.0)  # 128 telemetry batches while setpoints pour in
    finally:
        stop.set()
        thread.join()
    messages = b.received()
    echoes = of_type(messages, "POSITION_TARGET_LOCAL_NED")
    assert len(echoes) == len(taken) > 50 and len(messages) > len(echoes) + 100
    gaps = {(m2.get_seq() - m1.get_seq()) % 256 for m1, m2 in itertools.pairwise(messages)}
    assert gaps == {1}, gaps  # in the order sent, each frame is the next number
    b.endpoint.apply(taken, b.world.t)  # the loop flies them: the last one is the setpoint
    assert b.autopilot.state.sp_accel_ned[0][:2].tolist() == pytest.approx([0.1, 0.0])
    assert b.autopilot.state.sp_z_ned[0] == pytest.approx(-1.0)


def test_the_loop_gets_a_setpoint_before_its_echo_leaves() -> None:
    """A lockstep GCS acks once it has the echo: the loop must already hold the setpoint."""
    b = bench()
    frame = b.gcs.encode(accel_setpoint_message(
        target_system=SYSID, target_component=1, time_boot_ms=0, accel_xy_ned=(0.2, -0.1),
        z_ned=-1.5))
    sent_at_hand_over: list[int] = []
    taken = b.endpoint.take(frame, b.world.t,
                            lambda inbound: sent_at_hand_over.append(len(b.sent)))
    assert sent_at_hand_over == [0] and len(taken) == 1
    (echo,) = of_type(b.received(), "POSITION_TARGET_LOCAL_NED")
    assert (echo.afx, echo.afy) == pytest.approx((0.2, -0.1))


def test_a_retried_command_is_answered_again_but_carried_out_once() -> None:
    """A GCS resends a command whose ack it lost (confirmation 1, 2, ...): a take-off is not
    retargeted from where the first copy got to, and the answer is the first one's."""
    b = bench()
    b.run(0.05)
    b.command(ARM, 1)
    # below the taut rope (about 0.87 m); NaN yaw, as QGC and MAVSDK send it
    takeoff = [0.0, 0.0, 0.0, float("nan"), 0.0, 0.0, 0.4]
    b.send(b.gcs.mav.command_long_encode(SYSID, 1, TAKEOFF, 0, *takeoff))
    b.run(1.0)  # climbing: about 0.3 m up
    b.send(b.gcs.mav.command_long_encode(SYSID, 1, TAKEOFF, 1, *takeoff))  # ack was "lost"
    b.run(3.5)
    got = b.received()
    assert acks(got) == [(ARM, ACCEPTED), (TAKEOFF, ACCEPTED), (TAKEOFF, ACCEPTED)]
    assert of_type(got, "LOCAL_POSITION_NED")[-1].z == pytest.approx(-0.4, abs=0.1)  # not 0.7
    # a retry of a TEMPORARILY_REJECTED command is tried again: arming before any position
    fresh = bench()
    fresh.command(ARM, 1)
    fresh.run(0.05)
    fresh.send(fresh.gcs.mav.command_long_encode(SYSID, 1, ARM, 1, 1.0, 0, 0, 0, 0, 0, 0))
    assert acks(fresh.received()) == [(ARM, mavlink.MAV_RESULT_TEMPORARILY_REJECTED),
                                      (ARM, ACCEPTED)]


def test_command_int_is_answered_unsupported() -> None:
    b = bench()
    b.send(b.gcs.mav.command_int_encode(SYSID, 1, mavlink.MAV_FRAME_GLOBAL, TAKEOFF, 0, 0,
                                        0, 0, 0, 0, 0, 0, 10.0))
    assert acks(b.received()) == [(TAKEOFF, mavlink.MAV_RESULT_UNSUPPORTED)]
    assert b.autopilot.mode(0) is SimMode.DISARMED
