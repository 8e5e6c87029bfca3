"""The simulated vehicle as PX4 looks to other ground stations: its modes, parameters, GPS,
global position, home, origin and version, driven with real frames against real physics.

As in ``test_endpoint``, a GCS-side encoder writes the bytes and the
endpoint's frames are decoded back; the modes are named by pymavlink's own
``mavutil`` (what MAVProxy shows) and asked for with its ``px4_map``.
"""

from __future__ import annotations

import dataclasses
import math
import struct

import numpy as np
import pytest
from pymavlink import mavutil

from gcs.wire import (
    SIM_PX4_MODES,
    Geodetic,
    MavMessage,
    Px4MainMode,
    SimMode,
    geodetic_to_ned,
    mavlink,
    ned_to_geodetic,
    sim_mode_for_px4,
    sim_mode_of,
)
from tests.vehicles.test_endpoint import (
    ACCEPTED,
    ARM,
    CHUNK,
    DENIED,
    SET_MODE,
    SYSID,
    TAKEOFF,
    Bench,
    acks,
    bench,
    of_type,
    take_off,
    texts,
)
from vehicles import AutopilotConfig
from vehicles._params import PARAM_ID_LEN, ParamType, parameters
from vehicles.endpoint import DEFAULT_REFERENCE

REAL32 = mavlink.MAV_PARAM_TYPE_REAL32
INT32 = mavlink.MAV_PARAM_TYPE_INT32
START = (0.5, 0.5)
"""Where the bench's vehicle (the paper square's north-east corner) starts, m."""


def mode_request(b: Bench, name: str) -> None:
    """DO_SET_MODE as pymavlink's ``set_mode_px4`` sends it for ``name``."""
    b.command(SET_MODE, *mavutil.px4_map[name])


def modes_named(messages: list[MavMessage]) -> list[tuple[bool, str]]:
    """(armed, pymavlink's mode name) of each HEARTBEAT."""
    return [(bool(m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED), mavutil.mode_string_v10(m))
            for m in of_type(messages, "HEARTBEAT")]


def hold_stream(b: Bench, seconds: float, z: float = -1.0) -> None:
    """Setpoints at 4 Hz holding still at ``z``, as the GCS streams them."""
    for _ in range(round(seconds * 4)):
        b.setpoint((0.0, 0.0), z)
        b.run(0.25)


def param_values(messages: list[MavMessage]) -> dict[str, MavMessage]:
    return {m.param_id: m for m in of_type(messages, "PARAM_VALUE")}


def set_param(b: Bench, name: str, value: float, kind: int = REAL32) -> MavMessage:
    b.send(b.gcs.mav.param_set_encode(SYSID, 1, name.encode(), value, kind))
    (answer,) = of_type(b.received(), "PARAM_VALUE")
    assert answer.param_id == name
    return answer


def whole_texts(messages: list[MavMessage]) -> list[str]:
    """STATUSTEXTs with their MAVLink 2 chunks joined, in order."""
    out: list[str] = []
    chunked: dict[int, int] = {}
    for m in of_type(messages, "STATUSTEXT"):
        if m.id and m.id in chunked:
            out[chunked[m.id]] += m.text
        else:
            chunked[m.id] = len(out)
            out.append(m.text)
    return out


def int32(value: float) -> int:
    """An INT32 parameter's value, from its bytes in ``param_value`` (PX4's encoding)."""
    return int(struct.unpack("<i", struct.pack("<f", value))[0])


def geodetic(msg: MavMessage, lat: str = "lat", lon: str = "lon",
             alt: str = "alt") -> Geodetic:
    return Geodetic(getattr(msg, lat) / 1e7, getattr(msg, lon) / 1e7, getattr(msg, alt) / 1e3)


# -- modes ------------------------------------------------------------------------------------


def test_heartbeats_name_every_mode_as_pymavlink_does_and_px4_mode_requests_work() -> None:
    b = bench()
    b.run(0.05)
    assert modes_named(b.received())[-1] == (False, "LOITER")  # disarmed: PX4's Hold
    b.command(ARM, 1)
    b.command(TAKEOFF, 0, 0, 0, 0, 0, 0, 0.6)
    assert modes_named(b.received()) == [(True, "LOITER"), (True, "TAKEOFF")]
    b.run(3.0)
    assert modes_named(b.received())[-1] == (True, "LOITER")  # at altitude: Hold
    mode_request(b, "POSCTL")  # sticks centred: holds position, and says POSCTL
    got = b.received()
    assert acks(got) == [(SET_MODE, ACCEPTED)] and modes_named(got) == [(True, "POSCTL")]
    b.setpoint((0.0, 0.0), -0.6)
    mode_request(b, "OFFBOARD")
    assert modes_named(b.received()) == [(True, "OFFBOARD")]
    hold_stream(b, 1.0, -0.6)
    b.run(1.0)  # the stream stops: the failsafe holds, as AUTO.LOITER, not the POSCTL of before
    got = b.received()
    assert modes_named(got)[-1] == (True, "LOITER")
    assert "offboard" in " ".join(texts(got)).lower()
    b.send(b.gcs.mav.set_mode_encode(SYSID, mavutil.px4_map["ALTCTL"][0],
                                     Px4MainMode.ALTCTL << 16))  # the SET_MODE message
    got = b.received()
    assert acks(got) == [(SET_MODE, ACCEPTED)] and modes_named(got) == [(True, "ALTCTL")]
    for refused in ("MANUAL", "STABILIZED", "MISSION", "RTL"):
        mode_request(b, refused)
    got = b.received()
    assert acks(got) == [(SET_MODE, DENIED)] * 4 and modes_named(got) == []
    assert "set mode: MANUAL is not a mode of this vehicle" in whole_texts(got)
    mode_request(b, "LAND")
    assert modes_named(b.received()) == [(True, "LAND")]
    b.run(3.0)
    assert modes_named(b.received())[-1] == (False, "LOITER")
    assert b.autopilot.mode(0) is SimMode.DISARMED


def test_the_mode_table_reads_back_both_ways() -> None:
    """What the GCS's sim profile reads from a HEARTBEAT: PX4 modes, and the bare SimMode
    values of earlier simulators."""
    for mode, custom in SIM_PX4_MODES.items():
        assert sim_mode_of(custom, armed=mode is not SimMode.DISARMED) is mode
        assert sim_mode_of(int(mode)) is mode  # an earlier simulator's number
    names = {mode: mavutil.interpret_px4_mode(0, custom) for mode, custom in SIM_PX4_MODES.items()}
    assert names == {SimMode.DISARMED: "LOITER", SimMode.TAKEOFF: "TAKEOFF",
                     SimMode.HOLD: "LOITER", SimMode.OFFBOARD: "OFFBOARD", SimMode.LAND: "LAND"}
    assert [sim_mode_for_px4(*mavutil.px4_map[n][1:]) for n in ("POSCTL", "ALTCTL", "LOITER")] \
        == [SimMode.HOLD] * 3
    assert sim_mode_for_px4(Px4MainMode.MANUAL) is None and sim_mode_of(0x07040000) is None


def test_auto_takeoff_and_a_takeoff_without_altitude_climb_mis_takeoff_alt() -> None:
    b = bench()
    b.run(0.05)
    # a single vehicle below its rope's reach (0.87 m): it cannot lift the payload alone
    assert set_param(b, "MIS_TAKEOFF_ALT", 0.3).param_value == pytest.approx(0.3)
    mode_request(b, "TAKEOFF")  # disarmed: refused, as the kernel's take-off is
    assert acks(b.received()) == [(SET_MODE, DENIED)]
    b.command(ARM, 1)
    mode_request(b, "TAKEOFF")
    b.run(2.0)
    assert -b.world.p_ned[0, 2] == pytest.approx(0.3, abs=0.05)
    assert modes_named(b.received())[-1] == (True, "LOITER")
    b.command(TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, math.nan)  # as QGC sends it
    assert acks(b.received()) == [(TAKEOFF, ACCEPTED)]
    b.run(3.0)
    assert -b.world.p_ned[0, 2] == pytest.approx(0.3 + 0.3, abs=0.05)  # another 0.3 m up


# -- parameters -------------------------------------------------------------------------------


def test_every_parameter_is_listed_once_with_its_count_and_index() -> None:
    b = bench()
    b.send(b.gcs.mav.param_request_list_encode(SYSID, 1))
    values = of_type(b.received(), "PARAM_VALUE")
    count = values[0].param_count
    assert count == len(values) == len(parameters(SYSID)) >= 25
    assert sorted(m.param_index for m in values) == list(range(count))
    assert all(m.param_count == count for m in values)
    names = [m.param_id for m in sorted(values, key=lambda m: m.param_index)]
    assert names == sorted(names) and len(set(names)) == count
    assert all(len(n) <= PARAM_ID_LEN for n in names)
    got = param_values(values)
    assert got["MPC_TILTMAX_AIR"].param_value == pytest.approx(20.0)  # the bank limit, deg
    assert got["MPC_TILTMAX_AIR"].param_type == REAL32
    assert got["COM_OF_LOSS_T"].param_value == pytest.approx(0.5)
    assert {n: int32(got[n].param_value) for n in ("MAV_SYS_ID", "SYS_AUTOSTART",
                                                    "COM_RC_IN_MODE")} == {
        "MAV_SYS_ID": SYSID, "SYS_AUTOSTART": 4001, "COM_RC_IN_MODE": 4}
    assert all(got[n].param_type == INT32 for n in ("MAV_SYS_ID", "SYS_AUTOSTART"))
    # every setting of the autopilot is a parameter, and only one
    settings = [(p.setting, p.element) for p in parameters(SYSID) if p.setting is not None]
    assert len(settings) == len(set(settings))
    assert {s for s, _ in settings} == {f.name for f in dataclasses.fields(AutopilotConfig)}
    assert all(p.kind is ParamType.REAL32 for p in parameters(SYSID) if p.setting)


def test_a_set_changes_that_vehicles_running_autopilot_and_is_read_back() -> None:
    b = bench()
    answer = set_param(b, "MPC_TILTMAX_AIR", 12.0)
    assert answer.param_value == pytest.approx(12.0) and answer.param_type == REAL32
    assert b.autopilot.params.bank_max[0] == pytest.approx(math.radians(12.0))
    assert b.autopilot.params.bank_max[1] == pytest.approx(math.radians(20.0))  # the others
    assert b.autopilot.vehicle_config(0).bank_max_deg == pytest.approx(12.0)
    b.send(b.gcs.mav.param_request_read_encode(SYSID, 1, b"MPC_TILTMAX_AIR", -1))
    by_name = param_values(b.received())["MPC_TILTMAX_AIR"]
    b.send(b.gcs.mav.param_request_read_encode(SYSID, 1, b"", by_name.param_index))
    by_index = param_values(b.received())["MPC_TILTMAX_AIR"]
    assert by_name.param_value == by_index.param_value == pytest.approx(12.0)
    # flown at once: a hard push tilts no further than the new limit
    take_off(b, 0.6)
    hold_stream(b, 0.5, -0.6)
    b.command(SET_MODE, *mavutil.px4_map["OFFBOARD"])
    tilt = []
    for _ in range(8):
        b.setpoint((4.0, 0.0), -0.6)
        b.run(0.125)
        tilt.append(abs(b.autopilot.attitude_cmd[0, 1]))
    assert max(tilt) == pytest.approx(math.radians(12.0), abs=1e-9)


def test_refused_sets_answer_the_old_value_and_say_why() -> None:
    b = bench()
    before = b.autopilot.vehicle_config(0)
    for name, value, kind in [("MPC_TILTMAX_AIR", 95.0, REAL32),  # out of range
                              ("MPC_TILTMAX_AIR", math.nan, REAL32),
                              ("MPC_TILTMAX_AIR", 25.0, INT32),  # wrong type
                              ("INDI_LOOP_HZ", 256.0, REAL32),  # the team's, read-only
                              ("INDI_ATT_GAIN_X", -3.0, REAL32)]:
        b.send(b.gcs.mav.param_set_encode(SYSID, 1, name.encode(), value, kind))
    got = b.received()
    answers = [(m.param_id, m.param_value) for m in of_type(got, "PARAM_VALUE")]
    assert answers == [("MPC_TILTMAX_AIR", pytest.approx(20.0))] * 3 + [
        ("INDI_LOOP_HZ", 512.0), ("INDI_ATT_GAIN_X", 300.0)]
    assert whole_texts(got) == [
        "param set refused: MPC_TILTMAX_AIR: must be less than 90, got 95",
        "param set refused: MPC_TILTMAX_AIR: not a finite number",
        "param set refused: MPC_TILTMAX_AIR: is REAL32, not type 6",
        "param set refused: INDI_LOOP_HZ: read-only",
        "param set refused: INDI_ATT_GAIN_X: must be greater than 0, got -3"]
    assert b.autopilot.vehicle_config(0) == before
    b.send(b.gcs.mav.param_set_encode(SYSID, 1, b"MAV_SYS_ID", 2.0, INT32))
    (answer,) = of_type(got := b.received(), "PARAM_VALUE")
    assert int32(answer.param_value) == SYSID and whole_texts(got) == [
        "param set refused: MAV_SYS_ID: read-only"]
    b.send(b.gcs.mav.param_set_encode(SYSID, 1, b"NO_SUCH_PARAM", 1.0, REAL32))
    b.send(b.gcs.mav.param_request_read_encode(SYSID, 1, b"NO_SUCH_PARAM", -1))
    b.send(b.gcs.mav.param_request_read_encode(SYSID, 1, b"", 999))
    got = b.received()
    assert of_type(got, "PARAM_VALUE") == []
    assert whole_texts(got) == ["param set refused: NO_SUCH_PARAM: no such parameter",
                          "param read: no parameter 'NO_SUCH_PARAM'",
                          "param read: no parameter index 999"]


# -- GPS, global position, home, origin, version ----------------------------------------------


def test_global_position_and_gps_follow_the_truth_in_flight() -> None:
    b = bench()
    take_off(b, 0.6)
    hold_stream(b, 0.5, -0.6)
    b.command(SET_MODE, *mavutil.px4_map["OFFBOARD"])
    worst, checked = 0.0, 0
    b.received()
    for k in range(2 * 128):  # 2 s pulling east and back: compared when each is sent
        if k % 32 == 0:
            b.setpoint((0.0, 0.6 if k < 128 else -0.6), -0.6)
        b.run(CHUNK)
        for position in of_type(b.received(), "GLOBAL_POSITION_INT"):
            truth = b.world.p_ned[0]
            ned = geodetic_to_ned(geodetic(position), DEFAULT_REFERENCE)
            worst = max(worst, float(np.linalg.norm(ned - truth)))
            assert position.relative_alt / 1e3 == pytest.approx(-truth[2], abs=0.03)
            checked += 1
    assert checked == pytest.approx(20, abs=1)  # 10 Hz
    # 2 mm position noise, 1e-7 degree steps (11 mm north, 7 mm east) and one pose period
    assert worst < 0.03, worst
    assert b.world.p_ned[0, 1] - START[1] > 0.2  # it did move
    b.run(0.25)
    gps = of_type(b.received(), "GPS_RAW_INT")[-1]
    assert gps.fix_type == mavlink.GPS_FIX_TYPE_RTK_FIXED and gps.satellites_visible > 6
    ned = geodetic_to_ned(geodetic(gps), DEFAULT_REFERENCE)
    assert np.linalg.norm(ned - b.world.p_ned[0]) < 0.03
    assert gps.alt_ellipsoid == gps.alt and gps.eph == 1  # cm


def test_home_and_origin_are_sent_at_the_first_fix_and_home_again_at_arming() -> None:
    b = bench()
    b.run(0.05)
    got = b.received()
    (origin,) = of_type(got, "GPS_GLOBAL_ORIGIN")
    assert geodetic(origin, "latitude", "longitude", "altitude") == pytest.approx(
        DEFAULT_REFERENCE, abs=1e-7)  # one frame for the team: the world's origin
    (home,) = of_type(got, "HOME_POSITION")
    assert (home.x, home.y, home.z) == pytest.approx((*START, 0.0), abs=0.01)
    assert geodetic_to_ned(geodetic(home, "latitude", "longitude", "altitude"),
                           DEFAULT_REFERENCE) == pytest.approx((*START, 0.0), abs=0.01)
    take_off(b, 0.6)
    b.command(mavlink.MAV_CMD_NAV_LAND)
    b.run(3.0)
    b.received()
    b.world.state.p_ned[0, 0] += 0.2  # carried 20 cm north on the ground
    b.run(0.05)
    b.command(ARM, 1)
    (home,) = of_type(b.received(), "HOME_POSITION")  # a new home where it armed
    assert home.x == pytest.approx(START[0] + 0.2, abs=0.01)
    b.command(mavlink.MAV_CMD_GET_HOME_POSITION)
    got = b.received()
    assert acks(got) == [(mavlink.MAV_CMD_GET_HOME_POSITION, ACCEPTED)]
    assert of_type(got, "HOME_POSITION")[0].x == pytest.approx(home.x)


def test_set_gps_global_origin_rebases_the_local_frame_before_arming_only() -> None:
    b = bench()
    b.run(0.05)
    b.received()
    here = Geodetic(*ned_to_geodetic((*START, 0.0), DEFAULT_REFERENCE))
    b.send(b.gcs.mav.set_gps_global_origin_encode(
        SYSID, round(here.lat_deg * 1e7), round(here.lon_deg * 1e7), round(here.alt_m * 1e3)))
    got = b.received()
    (answer,) = of_type(got, "GPS_GLOBAL_ORIGIN")
    assert geodetic(answer, "latitude", "longitude", "altitude") == pytest.approx(here,
                                                                                  abs=1e-7)
    (home,) = of_type(got, "HOME_POSITION")  # the same place, now at the local origin
    assert (home.x, home.y) == pytest.approx((0.0, 0.0), abs=0.02)
    b.run(0.25)
    got = b.received()
    local = of_type(got, "LOCAL_POSITION_NED")[-1]
    assert (local.x, local.y, local.z) == pytest.approx((0.0, 0.0, 0.0), abs=0.02)
    ned = geodetic_to_ned(geodetic(of_type(got, "GLOBAL_POSITION_INT")[-1]), DEFAULT_REFERENCE)
    assert ned == pytest.approx((*START, 0.0), abs=0.02)  # the global position stays true
    # it flies in its own frame: a take-off holds the start of its local frame
    take_off(b, 0.6)
    assert b.autopilot.p_ned[0] == pytest.approx((0.0, 0.0, -0.6), abs=0.05)
    assert b.world.p_ned[0] == pytest.approx((*START, -0.6), abs=0.05)
    # armed: refused, answered with the origin in force
    b.received()
    b.send(b.gcs.mav.set_gps_global_origin_encode(SYSID, 520_000_000, 43_700_000, 0))
    b.send(b.gcs.mav.set_gps_global_origin_encode(SYSID, 950_000_000, 0, 0))  # lat 95 deg
    got = b.received()
    assert [geodetic(m, "latitude", "longitude", "altitude")
            for m in of_type(got, "GPS_GLOBAL_ORIGIN")] == [pytest.approx(here, abs=1e-7)] * 2
    assert whole_texts(got)[0] == "origin not changed: denied: vehicle is armed"
    assert whole_texts(got)[1].startswith(
        "origin not changed: SET_GPS_GLOBAL_ORIGIN: latitude")


def test_autopilot_version_and_requested_messages() -> None:
    b = bench()
    b.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_HOME_POSITION)  # no fix
    b.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_VFR_HUD)
    b.command(mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1)
    got = b.received()
    assert acks(got) == [(mavlink.MAV_CMD_REQUEST_MESSAGE,
                          mavlink.MAV_RESULT_TEMPORARILY_REJECTED),
                         (mavlink.MAV_CMD_REQUEST_MESSAGE, DENIED),
                         (mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, ACCEPTED)]
    (version,) = of_type(got, "AUTOPILOT_VERSION")
    assert version.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
    assert version.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
    assert not version.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST
    assert version.flight_sw_version >> 16 == 0x010E and version.uid == SYSID  # PX4 1.14
    b.run(0.05)
    b.received()
    for message in (mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION,
                    mavlink.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN, mavlink.MAVLINK_MSG_ID_SYS_STATUS):
        b.command(mavlink.MAV_CMD_REQUEST_MESSAGE, message)
    got = b.received()
    assert acks(got) == [(mavlink.MAV_CMD_REQUEST_MESSAGE, ACCEPTED)] * 3
    assert [m.get_type() for m in got if m.get_type() != "COMMAND_ACK"] == [
        "AUTOPILOT_VERSION", "GPS_GLOBAL_ORIGIN", "SYS_STATUS"]
