"""Autopilot profiles and commands against a scripted autopilot on UDP loopback.

The autopilot (:mod:`tests.support.scripted_autopilot`) is a thread speaking MAVLink 2
through ``pymavlink.mavutil``, as a real PX4 or ArduPilot on a UDP port would,
refusing what the real one would refuse and recording every violation of the
expected sequence, which the tests then require to be empty.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
import math
import re
import socket
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.config import LinkConfig
from gcs.link import CommandError, Link, LinkError, LinkManager
from gcs.link._link import DEFAULT_TELEMETRY_RATES_HZ
from gcs.link._profile_ardupilot import ArduPilotProfile
from gcs.link._profile_px4 import HOLD_ACCEL_MAX, Px4Profile, hold_accel
from gcs.link._profile_sim import SimProfile
from gcs.testing import team_key
from gcs.transport import MavutilTransport
from gcs.wire import (
    CommandResult,
    CopterMode,
    LocalPosition,
    Px4MainMode,
    SigningKey,
    SimMode,
)
from gcs.wire._setpoints import MASK_ACCEL, MASK_ACCEL_XY_POS_Z
from tests.support.scripted_autopilot import (
    ARM,
    DROP,
    GCS_SYSID,
    LAND,
    SET_MODE,
    TAKEOFF,
    VEHICLE,
    InProgress,
    first_time,
    start_peer,
)


@pytest.fixture
def udp_link() -> Iterator[Link]:
    transport = MavutilTransport("udpin:127.0.0.1:0")
    link = Link(VEHICLE, transport, gcs_system_id=GCS_SYSID, command_timeout_s=0.3,
                command_retries=2, gcs_heartbeat_period_s=0.2, timesync_period_s=0.0)
    with link:
        yield link


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


def test_px4_takeoff_stream_lasts_while_the_climb_is_waited_for_and_ends_after(
        udp_link: Link) -> None:
    """Four PX4 SIH quads took 6 s to climb to the take-off height; the take-off's stream,
    a bridge of ``handover_s`` (5 s), ran out first and PX4's offboard-loss failsafe sent
    them to RTL. The GCS waiting for the climb keeps it going; once it stops asking, the
    stream ends within ``handover_s`` (a GCS that hung does not stream for ever)."""
    peer = start_peer(udp_link, "px4")
    try:
        profile = Px4Profile(udp_link, handover_s=0.5)
        profile.takeoff(altitude_m=1.0)
        climbing_until = time.monotonic() + 1.5  # three bridges long
        while time.monotonic() < climbing_until:
            profile.keep_climbing()
            time.sleep(0.05)
        asked_last = time.monotonic()
        time.sleep(1.5)
    finally:
        peer.stop()
    assert peer.violations == []
    armed = peer.commands(ARM)[0].t
    times = [r.t for r in peer.setpoints() if r.t > armed]
    # 10 Hz; without keep_climbing the stream stopped 0.5 s in and the gap was 1.06 s
    assert max(b - a for a, b in itertools.pairwise(times + [asked_last])) < 0.7, times
    assert asked_last + 0.3 < times[-1] < asked_last + 1.1  # then handover_s, not 1.5 s


def test_px4_hold_stream_pulls_back_to_where_it_began_and_damps_the_drift() -> None:
    """Zero acceleration kept a drifting vehicle drifting (PX4 SIH: 2.8 m in a 15 s climb)."""
    assert hold_accel((0.0, 0.0), (0.0, 0.0), (0.0, 0.0)) == (0.0, 0.0)
    ax, ay = hold_accel((0.0, 0.0), (0.3, -0.2), (0.0, 0.0))  # drifting: braked
    assert ax < 0.0 < ay and math.isclose(ax, -0.3) and math.isclose(ay, 0.2)
    ax, ay = hold_accel((1.0, -2.0), (0.0, 0.0), (0.0, 0.0))  # away: pulled back
    assert ax < 0.0 < ay and math.isclose(ay / ax, -2.0)
    far = hold_accel((40.0, 30.0), (0.0, 0.0), (0.0, 0.0))
    assert math.isclose(math.hypot(*far), HOLD_ACCEL_MAX)
    assert hold_accel((math.nan, 0.0), (0.0, 0.0), (0.0, 0.0)) == (0.0, 0.0)


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


def test_ardupilot_answers_positions_only_with_a_setpoint_the_caller_sent(
        udp_link: Link) -> None:
    """The GCS loop asks for the vertical channel, then sends the setpoint. A position
    arriving in between was answered with the new altitude target and the horizontal
    acceleration of before: (0, 0) at the start of a stream (a CI run beside two CPU
    hogs caught it). Here the gap is held open for a second: no setpoint goes out until
    the caller's does, and every one after carries its acceleration."""
    peer = start_peer(udp_link, "ardupilot", flies=True)
    try:
        profile = ArduPilotProfile(udp_link)
        profile.takeoff(altitude_m=1.0)
        time.sleep(1.0)
        profile.vertical_setpoint(-2.0)  # asked, not sent yet
        time.sleep(1.0)  # 20 positions arrive meanwhile
        asked_only = list(peer.setpoints())
        start = time.monotonic()
        while time.monotonic() - start < 2.0:
            profile.send_setpoint(accel_xy_ned=(0.3, -0.2), z_ned=-2.0)
            time.sleep(0.25)
    finally:
        peer.stop()
    assert asked_only == []
    setpoints = peer.setpoints()
    assert len(setpoints) > 8  # the caller's, and one per position between them
    assert all((r.msg.afx, r.msg.afy) == pytest.approx((0.3, -0.2)) for r in setpoints)


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
                               "ATTITUDE, SYS_STATUS, ATTITUDE_TARGET, GLOBAL_POSITION_INT, "
                               "GPS_GLOBAL_ORIGIN, HOME_POSITION")),
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
        # a simulated vehicle's link is signed with the team key: so is the peer playing it
        peer = start_peer(link, kind, script=script, position_rate_hz=2.0,
                          signing_key=team_key() if kind == "sim" else None)
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
    # and what ties its local frame to the team frame (recorded in the .tlog too)
    assert asked == [(v20.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 50_000.0),
                     (v20.MAVLINK_MSG_ID_ATTITUDE, 50_000.0),
                     (v20.MAVLINK_MSG_ID_SYS_STATUS, 1_000_000.0),
                     (v20.MAVLINK_MSG_ID_ATTITUDE_TARGET, 250_000.0),
                     (v20.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 200_000.0),
                     (v20.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN, 2_000_000.0),
                     (v20.MAVLINK_MSG_ID_HOME_POSITION, 2_000_000.0)]
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
                     "SYS_STATUS, ATTITUDE_TARGET, GLOBAL_POSITION_INT, GPS_GLOBAL_ORIGIN, "
                     "HOME_POSITION"] * 2


def test_ardupilot_peer_refuses_arming_outside_guided(udp_link: Link) -> None:
    peer = start_peer(udp_link, "ardupilot")
    try:
        with pytest.raises(CommandError) as info:
            udp_link.command_long(ARM, (1.0,))
    finally:
        peer.stop()
    err = info.value
    assert err.result is CommandResult.DENIED and err.attempts == 1
    assert "vehicle 1" in str(err) and "MAV_CMD_COMPONENT_ARM_DISARM" in str(err)
    assert "DENIED" in str(err)
    assert len(peer.commands(ARM)) == 1  # a refusal is final: no retry


def test_ardupilot_arms_in_guided_and_takes_off_right_after(udp_link: Link) -> None:
    """The GCS's arm switches a copter in STABILIZE to GUIDED first (armed in STABILIZE, the
    copters flew their first seconds on the pilot's sticks); the take-off then sends only
    NAV_TAKEOFF, at once."""
    peer = start_peer(udp_link, "ardupilot")
    try:
        profile = ArduPilotProfile(udp_link)
        profile.arm()
        assert profile.mode_text() == "GUIDED" and udp_link.telemetry.heartbeat.armed  # type: ignore[union-attr]
        armed = time.monotonic()
        profile.takeoff(altitude_m=1.0)
        took_off = time.monotonic()
    finally:
        peer.stop()
    assert peer.violations == []
    sequence = [(int(r.msg.command), r.msg.param1, r.msg.param2) for r in peer.commands()
                if r.msg.command in (SET_MODE, ARM, TAKEOFF)]
    assert sequence == [(SET_MODE, 1.0, float(CopterMode.GUIDED)), (ARM, 1.0, 0.0),
                        (TAKEOFF, 0.0, 0.0)]
    assert took_off - armed < 0.5  # one command: nothing between arm and take-off


def test_ardupilot_rearms_a_copter_that_disarmed_itself_and_takes_off_at_once(
        udp_link: Link) -> None:
    """A copter left armed on the ground disarms itself (DISARM_DELAY): the take-off arms it
    again in GUIDED and sends NAV_TAKEOFF right after."""
    peer = start_peer(udp_link, "ardupilot", auto_disarm_s=0.6)
    try:
        profile = ArduPilotProfile(udp_link)
        profile.arm()
        udp_link.wait_for(lambda t: t.heartbeat is not None and not t.heartbeat.armed,
                          timeout_s=3.0, what="the copter to disarm itself")
        profile.takeoff(altitude_m=1.0)
    finally:
        peer.stop()
    assert peer.violations == []
    arms = peer.commands(ARM)
    takeoff = peer.commands(TAKEOFF)
    assert [int(r.msg.param2) for r in peer.commands(SET_MODE)] == [CopterMode.GUIDED]
    assert len(arms) == 2 and len(takeoff) == 1
    assert takeoff[0].t - arms[1].t < 0.5  # before it can disarm again


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
                       "ATTITUDE_TARGET": CommandResult.ACCEPTED,
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


def _heartbeat_frame() -> bytes:
    mav = v20.MAVLink(None, srcSystem=VEHICLE, srcComponent=1)
    msg = mav.heartbeat_encode(v20.MAV_TYPE_QUADROTOR, v20.MAV_AUTOPILOT_ARDUPILOTMEGA, 0,
                               int(CopterMode.STABILIZE), v20.MAV_STATE_STANDBY)
    return bytes(msg.pack(mav))


def _heard(link: Link, count: int, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while link.health.frames_received < count:
        assert time.monotonic() < deadline, f"{link.health.frames_received} frames, not {count}"
        time.sleep(0.02)


def test_a_tcp_peer_that_is_gone_is_said_once_and_backed_off(
        caplog: pytest.LogCaptureFixture, capfd: pytest.CaptureFixture[str]) -> None:
    """An autopilot that died (its TCP port closed, nothing listening): one warning, then
    reconnection attempts backing off (0.5, 1, 2, 4 s...), not "EOF on TCP socket" in a
    tight loop (118 MB of log in 40 s); once it listens again, the link hears it again."""
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    transport = MavutilTransport(f"tcp:127.0.0.1:{port}")
    caplog.set_level(logging.DEBUG, logger="gcs.transport._mavutil_transport")
    with Link(VEHICLE, transport, gcs_system_id=GCS_SYSID, gcs_heartbeat_period_s=0.1,
              timesync_period_s=0.0) as link:
        peer, _ = server.accept()
        peer.sendall(_heartbeat_frame())
        _heard(link, 1)
        peer.close()
        server.close()  # gone: reconnecting is refused
        time.sleep(4.0)
        warnings = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
        attempts, disconnects = transport.reconnect_attempts, transport.disconnects
        connected = transport.connected
        server = socket.create_server(("127.0.0.1", port))  # back
        server.settimeout(10.0)
        peer, _ = server.accept()
        peer.sendall(_heartbeat_frame())
        _heard(link, 2)
        peer.close()
        server.close()
        back = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
    printed = capfd.readouterr().out
    print(f"tcp peer gone 4 s: {len(warnings)} warning, {attempts} reconnection attempts")
    assert len(warnings) == 1, warnings
    assert re.fullmatch(rf"tcp:127\.0\.0\.1:{port}: (the peer closed the connection|connection "
                        r"lost \(.+\)); reconnecting, every 0\.5 s at first and at most every "
                        r"8 s", warnings[0]), warnings
    assert disconnects == 1 and 2 <= attempts <= 4, (disconnects, attempts)  # 0.5, 1.5, 3.5 s
    assert "EOF" not in printed and "Connection reset" not in printed, \
        f"{printed.count(chr(10))} lines printed: {printed[:60]!r}"
    assert not connected
    assert back[1].startswith(f"tcp:127.0.0.1:{port}: connected again after "), back


def _hang_up(peer: socket.socket) -> None:
    """A clean hang-up: the peer's FIN, then what the GCS sent meanwhile read until the GCS
    closes too (a close with unread heartbeats would reset the connection instead, which
    the link reports as a lost connection: seen beside CPU hogs)."""
    peer.shutdown(socket.SHUT_WR)
    peer.settimeout(5.0)
    with contextlib.suppress(OSError):
        while peer.recv(4096):
            pass
    peer.close()


def test_a_tcpin_link_takes_its_peer_back_after_it_hung_up(
        caplog: pytest.LogCaptureFixture) -> None:
    """The GCS listens (tcpin:); the autopilot hangs up and calls again: one warning, then the
    link hears it on the new connection (the old one no longer spins the reader)."""
    caplog.set_level(logging.WARNING, logger="gcs.transport._mavutil_transport")
    transport = MavutilTransport("tcpin:127.0.0.1:0")
    address = transport.local_address
    assert address is not None
    port = address[1]
    with Link(VEHICLE, transport, gcs_system_id=GCS_SYSID, gcs_heartbeat_period_s=0.1,
              timesync_period_s=0.0) as link:
        for call in (1, 2):
            peer = socket.create_connection(("127.0.0.1", port))
            peer.sendall(_heartbeat_frame())
            _heard(link, call)
            _hang_up(peer)
            time.sleep(0.5)
        spins = transport.read_errors
    texts = [r.getMessage() for r in caplog.records]
    assert texts[0] == ("tcpin:127.0.0.1:0: the peer closed the connection; waiting for it "
                        "to connect again"), texts
    assert texts[1].startswith("tcpin:127.0.0.1:0: connected again after") and len(texts) == 3
    assert spins == 0
