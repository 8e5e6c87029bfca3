"""Logs the replay and report tests are run on, built from real bytes.

Each is written by the real recorder from frames that pymavlink encodes
(through our encoder), or copied record by record out of a real `gcs fly`
recording; none is a mock of the reader's input.
"""

from __future__ import annotations

import math
from pathlib import Path

from pymavlink import mavutil

from gcs.flightlog import EARTH_RADIUS_M
from gcs.link.dialect import mavlink
from gcs.link.encoder import MavlinkEncoder
from gcs.link.modes import CUSTOM_MODE_ENABLED, SAFETY_ARMED
from gcs.logreader import TlogIndex
from gcs.recorder import TlogRecorder

VEHICLES = (1, 2, 3, 4)
"""The system ids of the short flight's vehicles (configs/bebop_square.yaml)."""

GUIDED = 4
"""ArduCopter's custom_mode number of GUIDED."""

HOME = (47.3977419, 8.5455938, 488.0)
"""Latitude, longitude (deg) and altitude (m) of the synthetic ArduPilot field."""


def raw_messages(path: Path) -> list:
    """Every message of the file, read by pymavlink (not by our reader)."""
    conn = mavutil.mavlink_connection(str(path), dialect="common")
    out = []
    while (m := conn.recv_match()) is not None:
        if m.get_type() != "BAD_DATA":
            out.append(m)
    return out


def plain_copy(flight: Path, out: Path) -> Path:
    """``flight`` as a plain autopilot log: the vehicles' frames re-recorded, nothing of the GCS."""
    rec = TlogRecorder(out, encoder=MavlinkEncoder(system_id=255, component_id=190), epoch=0.0)
    for m in raw_messages(flight):
        if m.get_srcSystem() in VEHICLES:
            rec.frame(m._timestamp, m.get_msgbuf())
    rec.close()
    return out


def with_frame(flight: Path, out: Path, t: float, frame: bytes) -> Path:
    """``flight`` with one more record (stamped ``t``, Unix s) at its place in time."""
    one = out.with_suffix(".one")
    rec = TlogRecorder(one, encoder=MavlinkEncoder(system_id=255, component_id=190), epoch=0.0)
    rec.frame(t, frame)
    rec.close()
    data = flight.read_bytes()
    index = TlogIndex.build(flight)
    after = int((index.t <= t).sum())  # the records are in time order
    at = int(index.offset[after]) - 8 if after < len(index) else len(data)
    out.write_bytes(data[:at] + one.read_bytes() + data[at:])
    one.unlink()
    return out


def ardupilot_log(path: Path, *, shared_origin: bool, placed: tuple[int, ...] = (1, 2, 3),
                  seconds: float = 6.0, rate: float = 10.0) -> Path:
    """Four ArduCopters and a GCS as a real telemetry log shows them, 10 Hz for ``seconds``.

    Every vehicle sends HEARTBEAT (ARDUPILOTMEGA, GUIDED, disarmed for its first
    second, then armed), ATTITUDE (banked 0.5 rad while disarmed, at most 0.2 rad
    when armed) and SYS_STATUS (battery 90 %, one less every 2 s). The ``placed``
    ones fly north side by side, vehicle s at 3 (s - 1) m east, and send
    GLOBAL_POSITION_INT and LOCAL_POSITION_NED too: their local origins are where
    each one started unless ``shared_origin`` (then the field's origin, as when a
    GCS sets one for all). The others send no position at all. A Mission Planner
    heartbeat (system 255, MAV_TYPE_GCS) is there too.
    """
    rec = TlogRecorder(path, encoder=MavlinkEncoder(system_id=255, component_id=190),
                       epoch=1_700_000_000.0)
    encs = {s: MavlinkEncoder(system_id=s, component_id=1) for s in VEHICLES}
    gcs = MavlinkEncoder(system_id=255, component_id=190)
    lat0, lon0, alt0 = HOME
    for k in range(round(seconds * rate)):
        t = k / rate
        armed = t >= 1.0
        if k % round(rate) == 0:
            rec.frame(t, gcs.encode(gcs.mav.heartbeat_encode(
                mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0, 3)))
        for s, enc in encs.items():
            base = CUSTOM_MODE_ENABLED | (SAFETY_ARMED if armed else 0)
            rec.frame(t, enc.encode(enc.mav.heartbeat_encode(
                mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, base, GUIDED,
                mavlink.MAV_STATE_ACTIVE, 3)))
            roll = 0.2 * math.sin(t + s) if armed else 0.5
            rec.frame(t, enc.encode(enc.mav.attitude_encode(
                k * 100, roll, 0.05, 0.1 * s, 0.0, 0.0, 0.0)))
            rec.frame(t, enc.encode(enc.mav.sys_status_encode(
                0, 0, 0, 500, 15800, -1, 90 - k // 20, 0, 0, 0, 0, 0, 0)))
            if s not in placed:
                continue
            north, east, down = 0.5 * t, 3.0 * (s - 1), -2.0
            lat = lat0 + math.degrees(north / EARTH_RADIUS_M)
            lon = lon0 + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(lat0))))
            rec.frame(t, enc.encode(enc.mav.global_position_int_encode(
                k * 100, round(lat * 1e7), round(lon * 1e7), round((alt0 - down) * 1e3),
                round(-down * 1e3), 50, 0, 0, 0)))
            east0 = 0.0 if shared_origin else east  # each started at (0, east)
            rec.frame(t, enc.encode(enc.mav.local_position_ned_encode(
                k * 100, north, east - east0, down, 0.5, 0.0, 0.0)))
    rec.close()
    return path
