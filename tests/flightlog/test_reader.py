"""The log index and flight log on crafted .tlog files: real frames (pymavlink through our
encoder), written by the real recorder, read back through the real index.

Each test builds the log a bug was found on: frames dropped from one vehicle,
a vehicle with a gimbal, a GCS whose senders share its system id, an autopilot
script sending NAMED_VALUE_INT, GLOBAL_POSITION_INT only, damaged bytes, ArduCopters
whose local frames have different origins and one that logged no position.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from gcs.flightlog import FlightLog, TlogIndex, TlogRecorder
from gcs.wire import CUSTOM_MODE_ENABLED, SAFETY_ARMED, MavlinkEncoder, SimMode, mavlink
from tests.support.logfiles import HOME, ardupilot_log, field_fix, raw_messages, true_position

EPOCH = 1_700_000_000.0
RATE = 10.0  # vehicle messages per second


def _recorder(path: Path, sysid: int = 245) -> TlogRecorder:
    return TlogRecorder(path, encoder=MavlinkEncoder(system_id=sysid, component_id=190),
                        epoch=EPOCH)


def _heartbeat(enc: MavlinkEncoder, mode: int = SimMode.HOLD, armed: bool = True,
               kind: int = mavlink.MAV_TYPE_QUADROTOR,
               autopilot: int = mavlink.MAV_AUTOPILOT_GENERIC) -> bytes:
    base = CUSTOM_MODE_ENABLED | (SAFETY_ARMED if armed else 0)
    return enc.encode(enc.mav.heartbeat_encode(kind, autopilot, base, mode, 4, 3))


def _local(enc: MavlinkEncoder, k: int) -> bytes:
    return enc.encode(enc.mav.local_position_ned_encode(k * 100, 0.1 * k, 0.0, -1.0,
                                                        1.0, 0.0, 0.0))


def test_link_losses_count_each_vehicle_component_and_leave_the_gcs_out(
        tmp_path: Path) -> None:
    path = tmp_path / "losses.tlog"
    rec = _recorder(path)
    autopilot = MavlinkEncoder(system_id=1, component_id=1)
    gimbal = MavlinkEncoder(system_id=1, component_id=154)
    other = MavlinkEncoder(system_id=2, component_id=1)
    gcs_link = MavlinkEncoder(system_id=245, component_id=190)  # a second GCS sender
    dropped = {10, 50, 51, 52, 290}  # frames of vehicle 1's autopilot that never arrived
    for k in range(600):  # past two wraps of the 8-bit sequence number
        t = k / RATE
        frame = _heartbeat(autopilot) if k % 10 == 0 else _local(autopilot, k)
        if k not in dropped:
            rec.frame(t, frame)
        rec.frame(t, gimbal.encode(gimbal.mav.attitude_encode(k, 0.0, 0.0, 0.0, 0, 0, 0)))
        rec.frame(t, _local(other, k))
        rec.frame(t, _heartbeat(gcs_link, kind=mavlink.MAV_TYPE_GCS,
                                autopilot=mavlink.MAV_AUTOPILOT_INVALID))
        if k % 10 == 0:  # the GCS's senders interleave, each with its own counter
            rec.text(t, f"tick {k}")
    rec.close()
    log = FlightLog.load(path)
    assert log.link_losses() == {(1, 1): len(dropped), (1, 154): 0, (2, 1): 0}
    assert 245 in log.ground and sorted(log.tracks) == [1, 2]
    # the GCS's streams alone would show thousands of "losses"
    assert sum(log.index.streams_lost([245]).values()) > 100


def test_a_vehicle_sending_named_values_is_still_a_vehicle(tmp_path: Path) -> None:
    """An autopilot script's NAMED_VALUE_INT must not make its vehicle the GCS."""
    path = tmp_path / "script.tlog"
    rec = _recorder(path, sysid=255)
    scripted = MavlinkEncoder(system_id=1, component_id=1)
    plain = MavlinkEncoder(system_id=2, component_id=1)
    for k in range(200):
        t = k / RATE
        for enc in (scripted, plain):
            rec.frame(t, _local(enc, k))
        for name in (b"phase", b"pump", b"state"):  # more of these than anything else
            rec.frame(t, scripted.encode(scripted.mav.named_value_int_encode(k, name, k)))
    rec.close()
    log = FlightLog.load(path)
    assert log.gcs_sysid is None and log.team is None and len(log.tick_t) == 0
    assert sorted(log.tracks) == [1, 2]
    assert any("guidance internals" in m for m in log.missing)


def test_the_recorders_gcs_is_found_by_its_team_header(tmp_path: Path) -> None:
    path = tmp_path / "ours.tlog"
    rec = _recorder(path, sysid=245)
    rec.array(0.0, "team", np.array([2, 1, 1, 2, 1, 2, 1.5, 2.0, 1.0]))
    vehicles = [MavlinkEncoder(system_id=s, component_id=1) for s in (1, 2)]
    for k in range(40):
        t = 0.25 * k
        for enc in vehicles:
            rec.frame(t, _local(enc, k))
            for _ in range(3):  # chatty scripts on the vehicles, phase named too
                rec.frame(t, enc.encode(enc.mav.named_value_int_encode(k, b"phase", 99)))
        rec.internals(t, arrays={"dist_err": np.array([0.01 * k])}, sticks=(0.0, 0.0, 0.0),
                      scale=1.0, altitude=1.0, phase=6)
    rec.close()
    log = FlightLog.load(path)
    assert log.gcs_sysid == 245 and log.team is not None and log.team["ids"] == (1, 2)
    assert sorted(log.tracks) == [1, 2] and len(log.tick_t) == 40
    assert set(log.phase.tolist()) == {6}


def test_global_positions_stand_in_for_local_ones(tmp_path: Path) -> None:
    path = tmp_path / "global.tlog"
    rec = _recorder(path, sysid=255)
    encs = {s: MavlinkEncoder(system_id=s, component_id=1) for s in (1, 2)}
    for k in range(50):
        t = k / RATE
        for s, enc in encs.items():
            # vehicle 2 three metres east of 1
            lat, lon, alt = field_fix(0.5 * k, 3.0 * (s - 1), -2.0)
            rec.frame(t, enc.encode(enc.mav.global_position_int_encode(
                k * 100, round(lat * 1e7), round(lon * 1e7), round(alt * 1e3),
                2000, 500, 0, -10, 0)))
    rec.close()
    log = FlightLog.load(path)
    assert sorted(log.tracks) == [1, 2]
    one, two = log.tracks[1], log.tracks[2]
    np.testing.assert_allclose(one.p_ned[0], [0.0, 0.0, 0.0], atol=0.02)
    np.testing.assert_allclose(one.p_ned[-1], [24.5, 0.0, 0.0], atol=0.02)
    np.testing.assert_allclose(two.p_ned[:, 1], 3.0, atol=0.02)
    np.testing.assert_allclose(two.v_ned[0], [5.0, 0.0, -0.1])
    assert log.origin is not None and any("GLOBAL_POSITION_INT" in m for m in log.missing)


def test_damaged_frames_and_stamps_are_left_out_and_counted(tmp_path: Path) -> None:
    path = tmp_path / "damaged.tlog"
    rec = _recorder(path, sysid=255)
    enc = MavlinkEncoder(system_id=1, component_id=1)
    for k in range(100):
        rec.frame(k / RATE, _local(enc, k))
    rec.close()
    data = bytearray(path.read_bytes())
    index = TlogIndex.build(path)
    off = index.offset.astype(int)
    data[off[20] + 5] = 252  # a sender's id: without the checksum, a system 252 appears
    data[off[40] - 8 + 2] ^= 0x10  # the stamp's third byte: about 2**36 us (19 h) later
    path.write_bytes(bytes(data))
    index = TlogIndex.build(path)
    assert index.systems() == [1]
    assert len(index) == 98 and index.skipped_bytes > 0 and index.rejected_times == 1
    assert np.all(np.diff(index.t) > 0) and index.t[-1] - index.t[0] == pytest.approx(9.9)
    log = FlightLog.load(path)
    assert log.link_losses() == {(1, 1): 2}  # the two damaged records are missing frames


def _distances(log: FlightLog, ids: tuple[int, ...]) -> np.ndarray:
    """Distances between the vehicles ``ids`` at each sample, m (they sample together)."""
    p = np.stack([log.tracks[s].p_ned for s in ids])
    return np.linalg.norm(p[:, None] - p[None, :], axis=3)


def _true_distances(ids: tuple[int, ...], samples: int) -> np.ndarray:
    """What :func:`_distances` must give on :func:`ardupilot_log`: 3 m apart east."""
    p = np.array([[true_position(s, k / RATE) for k in range(samples)] for s in ids])
    return np.linalg.norm(p[:, None] - p[None, :], axis=3)


def _placing(log: FlightLog) -> list[str]:
    """The ``missing`` lines that say a vehicle was placed from GLOBAL_POSITION_INT."""
    return [m for m in log.missing if "GLOBAL_POSITION_INT about" in m]


@pytest.mark.parametrize("shared_origin", [False, True])
def test_ardupilot_vehicles_are_placed_in_one_frame(tmp_path: Path, shared_origin: bool) -> None:
    """Each ArduCopter's LOCAL_POSITION_NED is about its own origin (where its estimator
    started), so three vehicles flying 3 m apart all read (0, 0) there: they are placed
    from GLOBAL_POSITION_INT then, about vehicle 1's first fix; with a shared origin,
    from their local positions."""
    path = ardupilot_log(tmp_path / "ap.tlog", shared_origin=shared_origin)
    stages: dict[str, list[tuple[int, int]]] = {}
    log = FlightLog.load(path, progress=lambda stage, done, total:
                         stages.setdefault(stage, []).append((done, total)))
    # the tracks' progress: every vehicle message decoded for them, one step per vehicle
    placed, unplaced = 5 * 60, 3 * 60  # 60 of each type; vehicle 4 sends 3 types of 5
    total = 3 * placed + unplaced
    assert stages["tracks"] == [(k * placed, total) for k in (1, 2, 3)] + [(total, total)]
    assert sorted(log.tracks) == [1, 2, 3, 4] and log.ground == {255}
    zero = np.zeros(3) if shared_origin else np.array(true_position(1, 0.0))
    for s in (1, 2, 3):
        truth = np.array([true_position(s, k / RATE) for k in range(60)]) - zero
        np.testing.assert_allclose(log.tracks[s].p_ned, truth, atol=0.02)
        if shared_origin:
            local = [(m.x, m.y, m.z) for m in raw_messages(path)
                     if m.get_type() == "LOCAL_POSITION_NED" and m.get_srcSystem() == s]
            np.testing.assert_array_equal(log.tracks[s].p_ned, np.array(local, np.float32))
    if shared_origin:
        assert log.origin is None and log.origin_spread < 0.05 and _placing(log) == []
    else:
        assert log.origin is not None and log.origin_spread == pytest.approx(6.0, abs=0.02)
        lat, lon, alt = field_fix(*true_position(1, 0.0))
        assert _placing(log) == [
            "a shared local frame (the vehicles' LOCAL_POSITION_NED origins differ by up to "
            f"6.0 m): drawn from GLOBAL_POSITION_INT about {lat:.6f}, {lon:.6f}, "
            f"{alt:.1f} m, WGS-84"]
    four = log.tracks[4]  # attitude, mode and battery, no position: kept
    assert len(four.t) == 0 and len(four.att_t) == 60 and four.mode(-1) == "GUIDED"
    assert bool(four.armed[-1]) and four.battery[-1] == 88.0
    assert "vehicle positions from vehicle 4 (no LOCAL_POSITION_NED or GLOBAL_POSITION_INT)" \
        in log.missing
    metrics = log.telemetry_metrics()
    assert metrics["duration_s"] == pytest.approx(5.9, abs=1e-3)
    worst = max(math.acos(math.cos(0.2 * math.sin(k / RATE + s)) * math.cos(0.05))
                for k in range(10, 60) for s in (1, 2, 3, 4))  # armed from 1 s on
    assert metrics["worst_bank_rad"] == pytest.approx(worst, abs=1e-4)  # not the 0.5 disarmed


@pytest.mark.parametrize(("shared_origin", "both"), [(True, (1, 2)), (False, (1, 2)), (True, ())])
def test_a_vehicle_with_one_kind_of_position_joins_the_team_frame(
        tmp_path: Path, shared_origin: bool, both: tuple[int, ...]) -> None:
    """Vehicle 3 sends only GLOBAL_POSITION_INT, vehicle 4 only LOCAL_POSITION_NED, beside
    vehicles sending ``both``. With a shared origin measured, 3 is placed about it (not
    about vehicle 1's first fix, 4.5 m away and 2 m up) and 4 from its local
    positions; else the team is placed from GPS and 4, whose origin is unknown, nowhere."""
    path = ardupilot_log(tmp_path / "mixed.tlog", shared_origin=shared_origin, placed=both,
                         gps_only=(3,) if both else (1, 2, 3), local_only=(4,))
    log = FlightLog.load(path)
    if shared_origin and both:
        ids = (1, 2, 3, 4)
        truth = np.array([true_position(3, k / RATE) for k in range(60)])  # about HOME
        np.testing.assert_allclose(log.tracks[3].p_ned, truth, atol=0.03)
        assert log.origin is not None and log.origin_spread < 0.05 and log.own_frame == ()
        lat, lon, alt = HOME
        assert _placing(log) == [
            "local positions from vehicle 3 (about the others' local origin): drawn from "
            f"GLOBAL_POSITION_INT about {lat:.6f}, {lon:.6f}, {alt:.1f} m, WGS-84"]
    else:
        ids = (1, 2, 3)
        assert len(log.tracks[4].t) == 0 and len(log.tracks[4].att_t) == 60
        assert log.own_frame == (4,) and log.from_global == (1, 2, 3)
        why = ("the vehicles' LOCAL_POSITION_NED origins differ by up to 3.0 m" if both else
               "no vehicle sent both LOCAL_POSITION_NED and GLOBAL_POSITION_INT, to tie the two")
        assert _placing(log)[0].startswith(f"a shared local frame ({why}): ")
        assert ("vehicle positions from vehicle 4 in the team's frame (only LOCAL_POSITION_NED, "
                "about an origin no GLOBAL_POSITION_INT ties to the others'): not placed"
                in log.missing)
        assert not any("(no LOCAL_POSITION_NED or" in m for m in log.missing)
    np.testing.assert_allclose(_distances(log, ids), _true_distances(ids, 60), atol=0.03)
