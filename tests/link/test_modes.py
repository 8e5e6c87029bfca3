"""Mode numbers, command results, the ArduPilot vertical loop and presence bookkeeping."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.link import CommandError, Presence
from gcs.link._discovery import Discovery, PresenceSource
from gcs.link._profile_ardupilot import VerticalPd
from gcs.transport import ZenohSettings
from gcs.transport._zenoh_session import zenoh_config
from gcs.wire import (
    CommandResult,
    CopterMode,
    Px4AutoSubMode,
    Px4MainMode,
    SimMode,
    command_name,
    message_id,
    px4_mode_text,
)
from gcs.wire._dialect import message_name
from gcs.wire._modes import px4_custom_mode


def test_sim_modes_are_defined_once_and_readable() -> None:
    assert [(m.name, int(m)) for m in SimMode] == [
        ("DISARMED", 1), ("TAKEOFF", 2), ("HOLD", 3), ("OFFBOARD", 4), ("LAND", 5)]
    assert SimMode.OFFBOARD.text == "tracking external acceleration setpoints"


def test_px4_custom_mode_packing_matches_px4() -> None:
    assert px4_custom_mode(Px4MainMode.OFFBOARD) == 6 << 16 == 0x60000
    assert px4_custom_mode(Px4MainMode.AUTO, Px4AutoSubMode.LAND) == (4 << 16) | (6 << 24)
    assert px4_mode_text(0x60000) == "OFFBOARD"
    assert px4_mode_text(px4_custom_mode(Px4MainMode.AUTO, Px4AutoSubMode.TAKEOFF)) == (
        "AUTO.TAKEOFF")
    assert px4_mode_text(42 << 16) == "PX4 mode 42.0"


def test_ardupilot_mode_numbers() -> None:
    assert (CopterMode.GUIDED, CopterMode.LAND, CopterMode.STABILIZE) == (4, 9, 0)
    assert CopterMode.ALT_HOLD.text == "Alt Hold"


def test_command_results_from_the_wire_and_error_text() -> None:
    assert CommandResult.from_wire(v20.MAV_RESULT_DENIED) is CommandResult.DENIED
    assert CommandResult.from_wire(77) is CommandResult.UNKNOWN
    assert CommandResult.from_wire(255) is CommandResult.UNKNOWN  # TIMEOUT is ours, not wire
    err = CommandError(4, v20.MAV_CMD_DO_SET_MODE, CommandResult.DENIED, attempts=1,
                       timeout_s=1.0)
    assert str(err) == ("vehicle 4: MAV_CMD_DO_SET_MODE denied by the vehicle (DENIED) "
                        "after 1 attempt")
    assert isinstance(err, RuntimeError) and err.sysid == 4
    assert command_name(99999) == "MAV_CMD(99999)"


def test_message_names() -> None:
    assert message_id("local_position_ned") == 32 and message_name(32) == "LOCAL_POSITION_NED"
    with pytest.raises(ValueError, match="unknown MAVLink message 'NOPE'"):
        message_id("NOPE")


def test_vertical_pd_signs_gains_and_limits() -> None:
    pd = VerticalPd(kp=1.0, kd=1.4, az_max=2.0)
    # 1 m too low (z larger than the reference): accelerate up, i.e. negative down.
    assert pd.accel_down(z_ref_ned=-2.0, z_ned=-1.0, vz_ned=0.0) == pytest.approx(-1.0)
    # Climbing at 0.5 m/s at the reference: brake (positive down).
    assert pd.accel_down(z_ref_ned=-2.0, z_ned=-2.0, vz_ned=-0.5) == pytest.approx(0.7)
    assert pd.accel_down(z_ref_ned=-20.0, z_ned=0.0, vz_ned=0.0) == -2.0
    assert pd.accel_down(z_ref_ned=20.0, z_ned=0.0, vz_ned=0.0) == 2.0
    with pytest.raises(ValueError, match="not finite"):
        pd.accel_down(z_ref_ned=float("nan"), z_ned=0.0, vz_ned=0.0)


def test_vertical_pd_settles_a_double_integrator_at_4_hz() -> None:
    pd = VerticalPd()
    z, vz, dt = 0.0, 0.0, 0.25
    for _ in range(80):  # 20 s of the GCS loop
        az = pd.accel_down(z_ref_ned=-1.5, z_ned=z, vz_ned=vz)
        z, vz = z + vz * dt + 0.5 * az * dt * dt, vz + az * dt
    assert z == pytest.approx(-1.5, abs=0.01) and abs(vz) < 0.01


def test_discovery_reports_changes_only_and_names_missing() -> None:
    now = [0.0]
    got = []
    d = Discovery([1, 2, 3], clock=lambda: now[0], on_event=got.append)
    assert d.missing() == (1, 2, 3)
    assert d.report(1, True, PresenceSource.HEARTBEAT) is not None
    assert d.report(1, True, PresenceSource.HEARTBEAT) is None  # no change, no event
    d.report(1, True, PresenceSource.LIVELINESS)
    d.report(1, False, PresenceSource.HEARTBEAT)
    assert d.present() == {1}  # the token still vouches
    d.report(7, True, PresenceSource.LIVELINESS)
    assert d.missing() == (2, 3) and d.missing_text() == "configured vehicles not seen: 2, 3"
    assert [(e.sysid, e.presence, e.configured) for e in got] == [
        (1, Presence.APPEARED, True), (1, Presence.APPEARED, True),
        (1, Presence.VANISHED, True), (7, Presence.APPEARED, False)]
    assert got[2].text == "vehicle 1 vanished (MAVLink heartbeat)"
    assert len(d.events()) == 4 and d.events() == []


def test_zenoh_config_is_peer_on_loopback_without_multicast() -> None:
    config = zenoh_config(listen=("tcp/127.0.0.1:17447",), connect=())
    assert config.get_json("mode") == '"peer"'
    assert config.get_json("scouting/multicast/enabled") == "false"
    assert "tcp/127.0.0.1:17447" in config.get_json("listen/endpoints")
    assert ZenohSettings().connect == ("tcp/127.0.0.1:7447",)
    with pytest.raises(ValueError, match="client mode needs"):
        ZenohSettings(mode="client", connect=())
