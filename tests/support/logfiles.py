"""Logs the replay and report tests are run on, built from real bytes.

Each is written by the real recorder from frames that pymavlink encodes
(through our encoder), or copied record by record out of a real `gcs fly`
recording; none is a mock of the reader's input.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from pymavlink import mavutil

from gcs.flightlog import TlogIndex, TlogRecorder
from gcs.wire import CUSTOM_MODE_ENABLED, SAFETY_ARMED, MavlinkEncoder, mavlink, ned_to_geodetic

VEHICLES = (1, 2, 3, 4)
"""The system ids of the short flight's vehicles (configs/bebop_square.yaml)."""

GUIDED = 4
"""ArduCopter's custom_mode number of GUIDED."""

HOME = (47.3977419, 8.5455938, 488.0)
"""Latitude, longitude (deg) and altitude (m) of the synthetic ArduPilot field."""

START = (4.0, -2.0)
"""North, east (m) from HOME where vehicle 1 of :func:`ardupilot_log` takes off: not at
HOME, the origin a GCS sets for all, so a frame about a vehicle's first fix is told apart."""


def true_position(sysid: int, t: float) -> tuple[float, float, float]:
    """Where vehicle ``sysid`` of :func:`ardupilot_log` is ``t`` s in: NED about HOME, m."""
    return START[0] + 0.5 * t, START[1] + 3.0 * (sysid - 1), -2.0


def field_fix(north: float, east: float, down: float) -> tuple[float, float, float]:
    """Latitude, longitude (deg) and altitude (m) of a point NED about HOME (WGS-84)."""
    lat, lon, alt = ned_to_geodetic((north, east, down), HOME)
    return float(lat), float(lon), float(alt)


def raw_messages(path: Path, dialect: str = "common") -> list[Any]:
    """Every message of the file, read by pymavlink (not by our reader) in ``dialect``."""
    conn = mavutil.mavlink_connection(str(path), dialect=dialect)
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
                  gps_only: tuple[int, ...] = (), local_only: tuple[int, ...] = (),
                  seconds: float = 6.0, rate: float = 10.0) -> Path:
    """Four ArduCopters and a GCS as a real telemetry log shows them, 10 Hz for ``seconds``.

    Every vehicle sends HEARTBEAT (ARDUPILOTMEGA, GUIDED, disarmed for its first
    second, then armed), ATTITUDE (banked 0.5 rad while disarmed, at most 0.2 rad
    when armed) and SYS_STATUS (battery 90 %, one less every 2 s). Each vehicle
    flies north side by side with the others (:func:`true_position`, 3 m apart
    east, 2 m up); the ``placed`` ones send GLOBAL_POSITION_INT and
    LOCAL_POSITION_NED, the ``gps_only`` ones only the first, the ``local_only``
    ones only the second. Local origins are where each one started (on the
    ground) unless ``shared_origin`` (then HOME, as when a GCS sets one for all).
    The others send no position at all. A Mission Planner heartbeat (system 255,
    MAV_TYPE_GCS) is there too.
    """
    rec = TlogRecorder(path, encoder=MavlinkEncoder(system_id=255, component_id=190),
                       epoch=1_700_000_000.0)
    encs = {s: MavlinkEncoder(system_id=s, component_id=1) for s in VEHICLES}
    gcs = MavlinkEncoder(system_id=255, component_id=190)
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
            north, east, down = true_position(s, t)
            if s in (*placed, *gps_only):
                lat, lon, alt = field_fix(north, east, down)
                rec.frame(t, enc.encode(enc.mav.global_position_int_encode(
                    k * 100, round(lat * 1e7), round(lon * 1e7), round(alt * 1e3),
                    round(-down * 1e3), 50, 0, 0, 0)))
            if s in (*placed, *local_only):
                n0, e0, _ = (0.0, 0.0, 0.0) if shared_origin else true_position(s, 0.0)
                rec.frame(t, enc.encode(enc.mav.local_position_ned_encode(
                    k * 100, north - n0, east - e0, down, 0.5, 0.0, 0.0)))
    rec.close()
    return path
