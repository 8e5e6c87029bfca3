"""Autopilot profiles and commands against a scripted autopilot on UDP loopback.

The autopilot is a thread speaking MAVLink 2 through ``pymavlink.mavutil``,
as a real PX4 or ArduPilot on a UDP port would. It answers commands, streams
HEARTBEAT and LOCAL_POSITION_NED, enforces the rules each autopilot imposes
(refusing what the real one would refuse) and records every violation of the
expected sequence, which the tests then require to be empty.
"""

from __future__ import annotations

import itertools
import math
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.config import LinkConfig
from gcs.link import CommandError, Link, LinkError, LinkManager
from gcs.link._link import DEFAULT_TELEMETRY_RATES_HZ
from gcs.link._profile_ardupilot import ArduPilotProfile
from gcs.link._profile_px4 import Px4Profile
from gcs.link._profile_sim import SimProfile
from gcs.transport import MavutilTransport
from gcs.wire import (
    CommandResult,
    CopterMode,
    LocalPosition,
    Px4AutoSubMode,
    Px4MainMode,
    SigningKey,
    SimMode,
)
from gcs.wire._modes import px4_custom_mode
from gcs.wire._setpoints import MASK_ACCEL, MASK_ACCEL_XY_POS_Z

GCS_SYSID = 245
VEHICLE = 1
ARM = v20.MAV_CMD_COMPONENT_ARM_DISARM
SET_MODE = v20.MAV_CMD_DO_SET_MODE
TAKEOFF = v20.MAV_CMD_NAV_TAKEOFF
LAND = v20.MAV_CMD_NAV_LAND
AUTOPILOT = {"px4": v20.MAV_AUTOPILOT_PX4, "ardupilot": v20.MAV_AUTOPILOT_ARDUPILOTMEGA,
             "sim": v20.MAV_AUTOPILOT_GENERIC}
INITIAL_MODE = {"px4": px4_custom_mode(Px4MainMode.POSCTL), "ardupilot": CopterMode.STABILIZE,
                "sim": SimMode.DISARMED}


@dataclass
class Received:
    """One message the autopilot got from the GCS."""

    t: float
    msg: Any


@dataclass
class InProgress:
    """Script entry: answer IN_PROGRESS now and ``final`` after ``delay_s``."""

    delay_s: float
    final: int


DROP = None
"""Script entry: do not answer this copy of the command."""


class ScriptedAutopilot(threading.Thread):
    """Plays a PX4, ArduPilot or simulated autopilot over a mavutil UDP connection."""

    def __init__(self, kind: str, gcs_port: int, *, script: dict[int, list[Any]] | None = None,
                 signing_key: SigningKey | None = None, z_ned: float = 0.0,
                 position_rate_hz: float = 20.0, flies: bool = False) -> None:
        super().__init__(daemon=True, name=f"scripted-{kind}")
        self.kind = kind
        self.conn = mavutil.mavlink_connection(f"udpout:127.0.0.1:{gcs_port}",
                                               source_system=VEHICLE, source_component=1)
        # Speak MAVLink 2 from the first frame, whatever mavutil's global dialect is.
        self.conn.mav = v20.MAVLink(self.conn, srcSystem=VEHICLE, srcComponent=1)
        self.conn.mav.robust_parsing = True
        self.conn.WIRE_PROTOCOL_VERSION = "2.0"
        self.conn.first_byte = False
        if signing_key is not None:
            self.conn.setup_signing(signing_key.secret, sign_outgoing=True, link_id=7)
        self.script = {k: list(v) for k, v in (script or {}).items()}
        self.lock = threading.Lock()
        self.received: list[Received] = []
        self.violations: list[str] = []
        self.bad_frames = 0
        self.armed = False
        self.custom_mode = int(INITIAL_MODE[kind])
        self.z_ned = z_ned
        self.vz_ned = 0.0
        self.position_period_s = 1.0 / position_rate_hz
        """LOCAL_POSITION_NED period, s; SET_MESSAGE_INTERVAL changes it."""
        self.flies = flies
        """ArduPilot: armed in GUIDED, z follows the last setpoint's afz (z'' = afz) until
        GUID_TIMEOUT (3 s); else z jumps to the take-off altitude."""
        self._afz: tuple[float, float] | None = None  # (time, afz) of the last setpoint
        self._later: list[tuple[float, int, int]] = []
        self._quit = threading.Event()
        self._offboard_since: float | None = None

    # -- test-side queries ------------------------------------------------------------------

    def commands(self, command: int | None = None) -> list[Received]:
        with self.lock:
            return [r for r in self.received if r.msg.get_type() == "COMMAND_LONG"
                    and (command is None or r.msg.command == command)]

    def setpoints(self) -> list[Received]:
        with self.lock:
            return [r for r in self.received
                    if r.msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED"]

    def stop(self) -> None:
        self._quit.set()
        self.join(timeout=2.0)
        self.conn.close()

    # -- the autopilot ------------------------------------------------------------------------

    def run(self) -> None:
        next_beat = next_position = 0.0
        last = time.monotonic()
        while not self._quit.is_set():
            now = time.monotonic()
            self._fly(now - last, now)
            last = now
            if now >= next_beat:
                self._heartbeat()
                next_beat = now + 0.05
            if now >= next_position:  # on a fixed grid: the rate holds whatever the delays
                self._position()
                next_position = max(next_position + self.position_period_s, now - 0.1)
            for item in [x for x in self._later if x[0] <= now]:
                self._later.remove(item)
                self._ack(item[1], item[2])
            msg = self.conn.recv_match(blocking=True, timeout=0.01)
            if msg is None:
                continue
            if msg.get_type() == "BAD_DATA":
                self.bad_frames += 1
                continue
            if msg.get_srcSystem() != GCS_SYSID:
                self._violation(f"frame from system {msg.get_srcSystem()}, not the GCS")
                continue
            if self.conn.mav.signing.secret_key is not None and not msg.get_signed():
                self._violation(f"unsigned {msg.get_type()} on a signed link")
            with self.lock:
                self.received.append(Received(time.monotonic(), msg))
            if msg.get_type() == "COMMAND_LONG":
                self._command(msg)
            elif msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED":
                self._setpoint(msg)
            self._check_offboard_stream()

    def _heartbeat(self) -> None:
        base = v20.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (
            v20.MAV_MODE_FLAG_SAFETY_ARMED if self.armed else 0)
        self.conn.mav.heartbeat_send(v20.MAV_TYPE_QUADROTOR, AUTOPILOT[self.kind], base,
                                     self.custom_mode, v20.MAV_STATE_ACTIVE)

    def _position(self) -> None:
        self.conn.mav.local_position_ned_send(int(time.monotonic() * 1000) & 0xFFFFFFFF,
                                              0.0, 0.0, self.z_ned, 0.0, 0.0, self.vz_ned)

    def _fly(self, dt: float, now: float) -> None:
        """Vertical double integrator driven by afz, as a GUIDED copter given acceleration."""
        if not (self.flies and self.armed and self.custom_mode == CopterMode.GUIDED):
            return
        az = self._afz[1] if self._afz is not None and now - self._afz[0] < 3.0 else 0.0
        self.z_ned += self.vz_ned * dt + 0.5 * az * dt * dt
        self.vz_ned += az * dt

    def _interval(self, msg: Any) -> int:
        """SET_MESSAGE_INTERVAL: LOCAL_POSITION_NED's rate is honoured, the rest accepted."""
        if int(msg.param1) == v20.MAVLINK_MSG_ID_LOCAL_POSITION_NED and msg.param2 > 0:
            self.position_period_s = msg.param2 / 1e6
        return v20.MAV_RESULT_ACCEPTED

    def _violation(self, text: str) -> None:
        with self.lock:
            self.violations.append(text)

    def _ack(self, command: int, result: int) -> None:
        self.conn.mav.command_ack_send(command, result, 0, 0, GCS_SYSID, 190)

    def _command(self, msg: Any) -> None:
        queue = self.script.get(msg.command)
        if queue:
            entry = queue.pop(0)
            if entry is DROP:
                return
            if entry == v20.MAV_RESULT_ACCEPTED and msg.command == \
                    v20.MAV_CMD_SET_MESSAGE_INTERVAL:
                self._interval(msg)
            if isinstance(entry, InProgress):
                self._ack(msg.command, v20.MAV_RESULT_IN_PROGRESS)
                self._later.append((time.monotonic() + entry.delay_s, msg.command, entry.final))
                return
            self._ack(msg.command, entry)
            return
        result = getattr(self, f"_{self.kind}_command")(msg)
        self._ack(msg.command, result)

    # PX4: OFFBOARD only after >= 1 s of setpoints above 2 Hz.
    def _px4_command(self, msg: Any) -> int:
        if msg.command == SET_MODE:
            main, sub = int(msg.param2), int(msg.param3)
            if not int(msg.param1) & v20.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
                self._violation("DO_SET_MODE without the custom-mode flag")
                return v20.MAV_RESULT_DENIED
            if main == Px4MainMode.OFFBOARD:
                times = [r.t for r in self.setpoints()]
                now = time.monotonic()
                recent = [t for t in times if t >= now - 1.0]
                gaps = [b - a for a, b in itertools.pairwise(recent)]
                if not times or now - times[0] < 1.0 or len(recent) < 2 or max(gaps) > 0.5:
                    self._violation("OFFBOARD requested before 1 s of setpoints above 2 Hz")
                    return v20.MAV_RESULT_DENIED
                self._offboard_since = now
            self.custom_mode = px4_custom_mode(Px4MainMode(main),
                                               Px4AutoSubMode(sub) if sub else None)
            return v20.MAV_RESULT_ACCEPTED
        if msg.command == ARM:
            self.armed = msg.param1 == 1.0
            if self.armed and self._offboard_since is not None:
                self.z_ned = -1.5  # climbs to the streamed z
            return v20.MAV_RESULT_ACCEPTED
        if msg.command == LAND:
            self.custom_mode = px4_custom_mode(Px4MainMode.AUTO, Px4AutoSubMode.LAND)
            self._offboard_since = None
            return v20.MAV_RESULT_ACCEPTED
        if msg.command == v20.MAV_CMD_SET_MESSAGE_INTERVAL:
            return self._interval(msg)
        return v20.MAV_RESULT_UNSUPPORTED

    # ArduCopter: GUIDED before arming and take-off; take-off only when armed.
    def _ardupilot_command(self, msg: Any) -> int:
        if msg.command == SET_MODE:
            self.custom_mode = int(msg.param2)
            return v20.MAV_RESULT_ACCEPTED
        if msg.command == ARM:
            if msg.param1 == 1.0 and self.custom_mode != CopterMode.GUIDED:
                self._violation("arm requested outside GUIDED")
                return v20.MAV_RESULT_DENIED
            self.armed = msg.param1 == 1.0
            return v20.MAV_RESULT_ACCEPTED
        if msg.command == TAKEOFF:
            if self.custom_mode != CopterMode.GUIDED or not self.armed:
                self._violation("take-off requested unarmed or outside GUIDED")
                return v20.MAV_RESULT_DENIED
            self.z_ned = -msg.param7
            return v20.MAV_RESULT_ACCEPTED
        if msg.command == v20.MAV_CMD_SET_MESSAGE_INTERVAL:
            return self._interval(msg)
        return v20.MAV_RESULT_UNSUPPORTED

    # Simulated vehicles: modes of gcs.wire._modes.SimMode.
    def _sim_command(self, msg: Any) -> int:
        if msg.command == ARM:
            self.armed = msg.param1 == 1.0
            self.custom_mode = SimMode.DISARMED
            return v20.MAV_RESULT_ACCEPTED
        if msg.command == TAKEOFF:
            if not self.armed or msg.param7 <= 0:
                self._violation("take-off unarmed or without altitude")
                return v20.MAV_RESULT_DENIED
            self.custom_mode = SimMode.TAKEOFF
            self.z_ned = -msg.param7
            return v20.MAV_RESULT_ACCEPTED
        if msg.command == SET_MODE:
            sp = self.setpoints()
            if int(msg.param2) == SimMode.OFFBOARD and (
                    not sp or time.monotonic() - sp[-1].t > 0.5):
                self._violation("OFFBOARD without a fresh setpoint")
                return v20.MAV_RESULT_DENIED
            self.custom_mode = int(msg.param2)
            return v20.MAV_RESULT_ACCEPTED
        if msg.command == LAND:
            self.custom_mode = SimMode.LAND
            return v20.MAV_RESULT_ACCEPTED
        return v20.MAV_RESULT_UNSUPPORTED

    def _setpoint(self, msg: Any) -> None:
        if msg.coordinate_frame != v20.MAV_FRAME_LOCAL_NED:
            self._violation(f"setpoint frame {msg.coordinate_frame}")
        if self.kind in ("px4", "sim") and msg.type_mask != MASK_ACCEL_XY_POS_Z:
            self._violation(f"type_mask {msg.type_mask} is not x/y acceleration + z position")
        if self.kind == "ardupilot":
            if self.custom_mode != CopterMode.GUIDED:
                self._violation("setpoint outside GUIDED")
            for group in (0x7, 0x38, 0x1C0):  # ArduCopter: each group all axes or none
                if msg.type_mask & group not in (0, group):
                    self._violation(f"type_mask {msg.type_mask} splits a group")
            if msg.type_mask != MASK_ACCEL:
                self._violation(f"type_mask {msg.type_mask} is not acceleration only")
            self._afz = (time.monotonic(), msg.afz)

    def _check_offboard_stream(self) -> None:
        if self.kind != "px4" or self._offboard_since is None:
            return
        times = [r.t for r in self.setpoints()]
        if len(times) >= 2 and times[-1] - times[-2] > 0.9:  # COM_OF_LOSS_T is 1 s
            self._violation(f"setpoint gap of {times[-1] - times[-2]:.2f} s in OFFBOARD")


@pytest.fixture
def udp_link() -> Iterator[Link]:
    transport = MavutilTransport("udpin:127.0.0.1:0")
    link = Link(VEHICLE, transport, gcs_system_id=GCS_SYSID, command_timeout_s=0.3,
                command_retries=2, gcs_heartbeat_period_s=0.2, timesync_period_s=0.0)
    with link:
        yield link


def start_peer(link: Link, kind: str, **options: Any) -> ScriptedAutopilot:
    assert isinstance(link.transport, MavutilTransport)
    address = link.transport.local_address
    assert address is not None
    port = address[1]
    peer = ScriptedAutopilot(kind, port, **options)
    peer.start()
    link.wait_for(lambda t: t.heartbeat is not None and t.position is not None,
                  timeout_s=5.0, what="first telemetry")
    return peer


def first_time(records: list[Received]) -> float:
    assert records, "expected at least one message"
    return records[0].t


def test_px4_streams_a_second_of_setpoints_then_offboard_then_arm(udp_link: Link) -> None:
    peer = start_peer(udp_link, "px4")
    try:
        profile = Px4Profile(udp_link)
        profile.takeoff(altitude_m=1.5)
        assert profile.mode_text() == "OFFBOARD"
        assert udp_link.telemetry.heartbeat.armed  # type: ignore[union-attr]
        for _ in range(5):  # the 4 Hz GCS loop takes over
            profile.send_setpoint(accel_xy_ned=(0.3, -0.2), z_ned=-1.5)
            time.sleep(0.25)
        profile.land()
        assert profile.mode_text() == "AUTO.LAND"
    finally:
        peer.stop()
    assert peer.violations == []
    offboard = [r for r in peer.commands(SET_MODE) if int(r.msg.param2) == Px4MainMode.OFFBOARD]
    arm = peer.commands(ARM)
    assert len(offboard) == 1 and len(arm) == 1
    setpoints = peer.setpoints()
    before = [r for r in setpoints if r.t < offboard[0].t]
    assert offboard[0].t - first_time(before) >= 1.0
    assert len(before) >= 3  # above 2 Hz for a second
    assert offboard[0].t < arm[0].t < first_time(peer.commands(LAND))
    assert all(r.msg.type_mask == MASK_ACCEL_XY_POS_Z for r in setpoints)
    assert all(math.isclose(r.msg.z, -1.5) for r in setpoints)
    assert any(math.isclose(r.msg.afx, 0.3, abs_tol=1e-6) for r in setpoints)


def test_px4_refuses_offboard_without_setpoint_stream(udp_link: Link) -> None:
    peer = start_peer(udp_link, "px4")
    try:
        with pytest.raises(CommandError) as info:
            udp_link.command_long(SET_MODE, (1, Px4MainMode.OFFBOARD, 0))
    finally:
        peer.stop()
    assert info.value.result is CommandResult.DENIED
    assert peer.violations == ["OFFBOARD requested before 1 s of setpoints above 2 Hz"]


def test_ardupilot_guided_arm_takeoff_then_acceleration_only(udp_link: Link) -> None:
    peer = start_peer(udp_link, "ardupilot")
    try:
        profile = ArduPilotProfile(udp_link)
        profile.takeoff(altitude_m=2.0)
        assert profile.mode_text() == "GUIDED"
        udp_link.wait_for(lambda t: t.position is not None and t.position.p_ned[2] == -2.0,
                          timeout_s=3.0, what="climb")
        for _ in range(4):
            profile.send_setpoint(accel_xy_ned=(0.2, -0.1), z_ned=-2.5)
            time.sleep(0.05)
        profile.land()
        assert profile.mode_text() == "LAND"
    finally:
        peer.stop()
    assert peer.violations == []
    modes = [(r.t, int(r.msg.param2)) for r in peer.commands(SET_MODE)]
    assert [m for _, m in modes] == [CopterMode.GUIDED, CopterMode.LAND]
    guided_t = modes[0][0]
    arm_t = first_time(peer.commands(ARM))
    takeoff = peer.commands(TAKEOFF)
    assert guided_t < arm_t < takeoff[0].t < modes[1][0]
    assert takeoff[0].msg.param7 == 2.0
    setpoints = peer.setpoints()
    assert len(setpoints) >= 4  # the caller's four, and one per position while they stream
    for r in setpoints:
        assert r.msg.type_mask == MASK_ACCEL
        assert (r.msg.afx, r.msg.afy) == pytest.approx((0.2, -0.1))
        # 0.5 m below the target with no vertical speed: accelerate up (negative down).
        assert r.msg.afz == pytest.approx(-0.5, abs=1e-6)


def test_ardupilot_closes_the_vertical_loop_at_telemetry_rate(udp_link: Link) -> None:
    """The 4 Hz caller's setpoints are joined by one per position (20 Hz), which climb the
    copter to the target; none before the caller streams, none once it stopped."""
    positions: list[float] = []
    udp_link.add_record_listener(
        lambda r: positions.append(time.monotonic()) if isinstance(r, LocalPosition) else None)
    peer = start_peer(udp_link, "ardupilot", flies=True)
    try:
        profile = ArduPilotProfile(udp_link)
        profile.takeoff(altitude_m=1.0)
        time.sleep(1.0)  # climbing on its own: nothing to steer yet
        start = time.monotonic()
        while time.monotonic() - start < 10.0:
            profile.send_setpoint(accel_xy_ned=(0.3, -0.2), z_ned=-2.0)
            time.sleep(0.25)
        stopped = time.monotonic()
        time.sleep(1.5)
        z_end = peer.z_ned
    finally:
        peer.stop()
    assert peer.violations == []
    setpoints = peer.setpoints()
    assert setpoints[0].t >= start  # nothing while the caller did not stream
    window = (start + 1.0, stopped)
    sent = sum(1 for r in setpoints if window[0] <= r.t <= window[1])
    heard = sum(1 for t in positions if window[0] <= t <= window[1])
    caller = (window[1] - window[0]) / 0.25
    # one per position heard, plus the caller's own (a few may fall either side of the window)
    assert sent >= 0.9 * (heard + caller), (sent, heard, caller)
    assert heard > 3 * caller  # positions do come faster than the caller
    assert all((r.msg.afx, r.msg.afy) == pytest.approx((0.3, -0.2)) for r in setpoints)
    assert z_end == pytest.approx(-2.0, abs=0.05)
    assert setpoints[-1].t < stopped + profile.follow_s + 0.15  # stops with the caller


def test_ardupilot_position_setpoints_stop_when_the_copter_leaves_guided(udp_link: Link) -> None:
    """A copter switched to LAND by its pilot or a failsafe gets no more per-position
    setpoints, although the caller still streams."""
    peer = start_peer(udp_link, "ardupilot", flies=True)
    try:
        profile = ArduPilotProfile(udp_link)
        profile.takeoff(altitude_m=1.0)
        start = time.monotonic()
        landed_at = None
        while time.monotonic() - start < 4.0:
            if landed_at is None and time.monotonic() - start > 2.0:
                peer.custom_mode = int(CopterMode.LAND)  # the copter leaves GUIDED on its own
                landed_at = time.monotonic()
            profile.send_setpoint(accel_xy_ned=(0.0, 0.0), z_ned=-1.0)
            time.sleep(0.25)
        end = time.monotonic()
    finally:
        peer.stop()
    assert landed_at is not None
    times = [r.t for r in peer.setpoints()]
    before = sum(1 for t in times if start + 0.5 <= t <= landed_at) / (landed_at - start - 0.5)
    after = sum(1 for t in times if landed_at + 0.3 <= t <= end) / (end - landed_at - 0.3)
    assert before > 12.0 and after < 6.0, (before, after)  # only the caller's 4 Hz remain


@pytest.mark.parametrize(("kind", "script", "note"), [
    ("ardupilot", {}, ("info", "vehicle 1: telemetry rates set for LOCAL_POSITION_NED, "
                               "ATTITUDE, SYS_STATUS")),
    ("px4", {v20.MAV_CMD_SET_MESSAGE_INTERVAL: [
        v20.MAV_RESULT_ACCEPTED, v20.MAV_RESULT_UNSUPPORTED, DROP]},
     ("warning", "vehicle 1: telemetry rate not set for ATTITUDE (UNSUPPORTED), SYS_STATUS "
                 "(TIMEOUT): streamed at the autopilot's own rate")),
    ("sim", {}, None),
])
def test_manager_asks_a_real_autopilot_for_the_telemetry_the_gcs_reads(
        kind: str, script: dict[int, list[Any]], note: tuple[str, str] | None) -> None:
    notes: list[tuple[str, str]] = []
    noted = threading.Event()

    def on_note(level: str, text: str) -> None:
        notes.append((level, text))
        noted.set()

    positions: list[float] = []
    config = LinkConfig(sysid=VEHICLE, transport="udpin:127.0.0.1:0", profile=kind)
    with LinkManager([config], check_period_s=0.05, on_note=on_note) as manager:
        link = manager.links[VEHICLE]
        link.add_record_listener(lambda r: positions.append(time.monotonic())
                                 if isinstance(r, LocalPosition) else None)
        peer = start_peer(link, kind, script=script, position_rate_hz=2.0)
        try:
            noted.wait(3.0)
            time.sleep(0.5)
            since = time.monotonic()
            time.sleep(1.5)
            rate = sum(1 for t in positions if t >= since) / (time.monotonic() - since)
        finally:
            peer.stop()
    asked = [(int(r.msg.param1), r.msg.param2)
             for r in peer.commands(v20.MAV_CMD_SET_MESSAGE_INTERVAL)]
    if note is None:  # the simulated vehicles stream what the GCS needs: nothing asked
        assert asked == [] and notes == [] and rate < 5.0
        return
    assert notes == [note]
    # one attempt each (an unanswered request must not hold the command lock for long)
    assert asked == [(v20.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 50_000.0),
                     (v20.MAVLINK_MSG_ID_ATTITUDE, 50_000.0),
                     (v20.MAVLINK_MSG_ID_SYS_STATUS, 1_000_000.0)]
    assert peer.position_period_s == pytest.approx(0.05)
    assert rate > 8.0  # was 2 Hz before the request (20 Hz asked; loose for a busy machine)


def test_a_rebooted_autopilot_is_asked_for_its_rates_again() -> None:
    """An autopilot that vanished (a battery swap reboots it: it forgot the rates) is asked
    again when it comes back."""
    notes: list[str] = []
    config = LinkConfig(sysid=VEHICLE, transport="udpin:127.0.0.1:0", profile="ardupilot",
                        heartbeat_timeout_s=0.5)
    with LinkManager([config], check_period_s=0.05,
                     on_note=lambda level, text: notes.append(text)) as manager:
        link = manager.links[VEHICLE]
        for boot in (1, 2):
            peer = start_peer(link, "ardupilot", position_rate_hz=2.0)
            try:
                deadline = time.monotonic() + 5.0
                while len(notes) < boot and time.monotonic() < deadline:
                    time.sleep(0.05)
                assert peer.position_period_s == pytest.approx(0.05), f"boot {boot}"
            finally:
                peer.stop()
            deadline = time.monotonic() + 5.0
            while link.health.alive and time.monotonic() < deadline:
                time.sleep(0.05)
            time.sleep(0.2)  # the manager's check loop sees it gone
    assert notes == ["vehicle 1: telemetry rates set for LOCAL_POSITION_NED, ATTITUDE, "
                     "SYS_STATUS"] * 2


def test_ardupilot_peer_refuses_arming_outside_guided(udp_link: Link) -> None:
    peer = start_peer(udp_link, "ardupilot")
    try:
        with pytest.raises(CommandError) as info:
            ArduPilotProfile(udp_link).arm()
    finally:
        peer.stop()
    err = info.value
    assert err.result is CommandResult.DENIED and err.attempts == 1
    assert "vehicle 1" in str(err) and "MAV_CMD_COMPONENT_ARM_DISARM" in str(err)
    assert "DENIED" in str(err)
    assert len(peer.commands(ARM)) == 1  # a refusal is final: no retry


def test_profile_refuses_the_wrong_autopilot(udp_link: Link) -> None:
    peer = start_peer(udp_link, "ardupilot")
    try:
        with pytest.raises(LinkError, match="vehicle 1: reports autopilot "
                                            "MAV_AUTOPILOT_ARDUPILOTMEGA"):
            Px4Profile(udp_link).takeoff(altitude_m=1.0)
    finally:
        peer.stop()
    assert peer.commands() == []


def test_sim_profile_sequence_and_custom_modes(udp_link: Link) -> None:
    peer = start_peer(udp_link, "sim")
    try:
        profile = SimProfile(udp_link)
        profile.takeoff(altitude_m=1.0)
        assert profile.mode_text() == "TAKEOFF"
        udp_link.wait_for(lambda t: t.position is not None and t.position.p_ned[2] == -1.0,
                          timeout_s=3.0, what="climb")
        profile.start_offboard()
        assert profile.mode_text() == "OFFBOARD"
        profile.send_setpoint(accel_xy_ned=(0.1, 0.0), z_ned=-1.0)
        profile.land()
        profile.disarm()
        assert profile.mode_text() == "DISARMED"
    finally:
        peer.stop()
    assert peer.violations == []
    sequence = [(int(r.msg.command), r.msg.param1, r.msg.param2, r.msg.param7)
                for r in peer.commands() if r.msg.confirmation == 0]
    assert sequence == [(ARM, 1.0, 0.0, 0.0), (TAKEOFF, 0.0, 0.0, 1.0),
                        (SET_MODE, 1.0, float(SimMode.OFFBOARD), 0.0), (LAND, 0.0, 0.0, 0.0),
                        (ARM, 0.0, 0.0, 0.0)]


def test_timeout_retries_then_names_vehicle_command_and_result(udp_link: Link) -> None:
    peer = start_peer(udp_link, "ardupilot", script={TAKEOFF: [DROP, DROP, DROP]})
    try:
        t0 = time.monotonic()
        with pytest.raises(CommandError) as info:
            udp_link.command_long(TAKEOFF, (0, 0, 0, 0, 0, 0, 1.0))
        elapsed = time.monotonic() - t0
    finally:
        peer.stop()
    err = info.value
    assert isinstance(err, RuntimeError)
    assert err.result is CommandResult.TIMEOUT and err.attempts == 3 and err.sysid == 1
    assert str(err) == ("vehicle 1: MAV_CMD_NAV_TAKEOFF got no COMMAND_ACK (TIMEOUT) after "
                        "3 attempts of 0.3 s")
    assert [r.msg.confirmation for r in peer.commands(TAKEOFF)] == [0, 1, 2]
    assert elapsed >= 0.9


def test_retry_succeeds_after_lost_copies(udp_link: Link) -> None:
    peer = start_peer(udp_link, "ardupilot", script={ARM: [DROP, DROP]})
    try:
        ArduPilotProfile(udp_link).set_mode(CopterMode.GUIDED)
        ack = udp_link.command_long(ARM, (1.0,))
    finally:
        peer.stop()
    assert ack.result is CommandResult.ACCEPTED and ack.attempts == 3
    assert 0.0 < ack.rtt_s < 0.3
    assert [r.msg.confirmation for r in peer.commands(ARM)] == [0, 1, 2]
    assert udp_link.health.rtt_s == pytest.approx(ack.rtt_s)


def test_temporarily_rejected_is_retried_and_in_progress_waits(udp_link: Link) -> None:
    peer = start_peer(udp_link, "ardupilot", script={
        TAKEOFF: [v20.MAV_RESULT_TEMPORARILY_REJECTED, InProgress(0.5, v20.MAV_RESULT_ACCEPTED)]})
    try:
        ack = udp_link.command_long(TAKEOFF, (0, 0, 0, 0, 0, 0, 1.0))
    finally:
        peer.stop()
    assert ack.result is CommandResult.ACCEPTED and ack.attempts == 2
    assert ack.rtt_s >= 0.45  # waited past the 0.3 s timeout because of IN_PROGRESS
    assert len(peer.commands(TAKEOFF)) == 2


@pytest.mark.parametrize(("result", "name"), [(v20.MAV_RESULT_UNSUPPORTED, "UNSUPPORTED"),
                                              (v20.MAV_RESULT_FAILED, "FAILED")])
def test_other_refusals_are_final(udp_link: Link, result: int, name: str) -> None:
    peer = start_peer(udp_link, "ardupilot", script={LAND: [result]})
    try:
        with pytest.raises(CommandError, match=rf"MAV_CMD_NAV_LAND .*\({name}\) after 1 attempt$"):
            udp_link.command_long(LAND)
    finally:
        peer.stop()


def test_message_interval_requests(udp_link: Link) -> None:
    peer = start_peer(udp_link, "ardupilot", script={
        v20.MAV_CMD_SET_MESSAGE_INTERVAL: [v20.MAV_RESULT_ACCEPTED, v20.MAV_RESULT_ACCEPTED,
                                           v20.MAV_RESULT_UNSUPPORTED, v20.MAV_RESULT_ACCEPTED]})
    try:
        results = udp_link.request_telemetry({**DEFAULT_TELEMETRY_RATES_HZ, "HIGHRES_IMU": 10.0})
        udp_link.set_message_interval("ATTITUDE", rate_hz=0)
    finally:
        peer.stop()
    assert results == {"LOCAL_POSITION_NED": CommandResult.ACCEPTED,
                       "ATTITUDE": CommandResult.ACCEPTED,
                       "SYS_STATUS": CommandResult.UNSUPPORTED,
                       "HIGHRES_IMU": CommandResult.ACCEPTED}
    asked = [(int(r.msg.param1), r.msg.param2) for r in
             peer.commands(v20.MAV_CMD_SET_MESSAGE_INTERVAL)]
    assert asked[:2] == [(v20.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 50_000.0),
                         (v20.MAVLINK_MSG_ID_ATTITUDE, 50_000.0)]
    assert asked[-1] == (v20.MAVLINK_MSG_ID_ATTITUDE, -1.0)


def test_signed_link_interoperates_with_pymavlink_signing() -> None:
    key = SigningKey(bytes(range(1, 33)))
    transport = MavutilTransport("udpin:127.0.0.1:0")
    link = Link(VEHICLE, transport, gcs_system_id=GCS_SYSID, signing_key=key,
                command_timeout_s=0.3, gcs_heartbeat_period_s=0.2, timesync_period_s=0.0)
    with link:
        peer = start_peer(link, "ardupilot", signing_key=key)
        try:
            ArduPilotProfile(link).takeoff(altitude_m=1.0)
        finally:
            peer.stop()
        health = link.health
    assert peer.violations == []
    assert peer.conn.mav.signing.goodsig_count > 0 and peer.conn.mav.signing.badsig_count == 0
    assert health.refused_signature == 0 and health.frames_received > 0
