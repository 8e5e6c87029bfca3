"""The live team frame and the log reader place a vehicle with one geodesy
(``gcs.wire._geodetic``), to the same numbers.

The live frame (:class:`gcs.loop.TeamFrame`) hears real MAVLink bytes through real
links; the log reader (:class:`gcs.flightlog.FlightLog`) reads the same frames from
a .tlog written by the real recorder. Kilometres apart at 70 degrees north a flat
earth misplaces a vehicle by metres; on the ellipsoid both agree.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import socket
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from gcs.config import GeoPoint, TeamFrameConfig, load_team
from gcs.flightlog import FlightLog, TlogRecorder
from gcs.link import Link, make_profile
from gcs.loop import FleetTable, TeamFrame
from gcs.transport import MavutilTransport
from gcs.wire import (
    CUSTOM_MODE_ENABLED,
    Geodetic,
    MavlinkEncoder,
    geodetic_to_ned,
    mavlink,
    ned_to_geodetic,
)
from tests.support.paths import ROOT
from tests.support.paths import SQUARE as SQUARE_PATH

SQUARE = ROOT / SQUARE_PATH

FAR_NORTH = Geodetic(69.65, 18.95, 20.0)
"""A field at 70 degrees north, where a sphere of the equator's radius is 0.2-0.3 % off."""

FIELDS = {
    "metres apart": (Geodetic(47.397742, 8.545594, 488.0),
                     [(0.0, 0.0), (0.4, -0.3), (-1.2, 2.0), (5.0, 1.0)]),
    "kilometres apart, far north": (FAR_NORTH,
                                    [(0.0, 0.0), (3000.0, 4000.0), (-2500.0, 1500.0),
                                     (800.0, -5000.0)]),
}
"""Where each of four vehicles set its local origin (m north and east of the field's point)."""

STANDING = np.array([[0.3, -0.2, 0.0], [1.5, 0.5, -0.1], [-0.4, 2.0, 0.05], [0.0, -1.0, 0.0]])
"""Where each vehicle stands in its own local frame, m (it creeps 1 cm north a sample)."""

SAMPLES = 12  # pairs per vehicle: within the live frame's window, so both use every one
EARTH_RADIUS = 6.4e6  # m, about the largest radius of curvature below 70 degrees


def _vehicle_frames(field: Geodetic, origins: list[tuple[float, float]]
                    ) -> dict[int, list[tuple[float, bytes]]]:
    """Per vehicle (1-4), its frames as (s since start, bytes): a disarmed heartbeat, then
    LOCAL_POSITION_NED and GLOBAL_POSITION_INT of the same moment, 10 a second."""
    out = {}
    for index, (north, east) in enumerate(origins):
        vid = index + 1
        enc = MavlinkEncoder(system_id=vid, component_id=1)
        own = ned_to_geodetic((north, east, 0.0), field)
        frames = [(0.0, enc.encode(enc.mav.heartbeat_encode(
            mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_PX4, CUSTOM_MODE_ENABLED, 0,
            mavlink.MAV_STATE_STANDBY, 3)))]
        for k in range(SAMPLES):
            t = 0.05 + k / 10.0
            p = STANDING[index] + (0.01 * k, 0.0, 0.0)
            lat, lon, alt = ned_to_geodetic(p, own)
            frames.append((t, enc.encode(enc.mav.local_position_ned_encode(
                k * 100, *p, 0.0, 0.0, 0.0))))
            frames.append((t, enc.encode(enc.mav.global_position_int_encode(
                k * 100, round(lat * 1e7), round(lon * 1e7), round(alt * 1e3),
                round(-p[2] * 1e3), 0, 0, 0, 0))))
        out[vid] = frames
    return out


def _logged(path: Path, frames: dict[int, list[tuple[float, bytes]]]) -> FlightLog:
    rec = TlogRecorder(path, encoder=MavlinkEncoder(system_id=245, component_id=190),
                       epoch=1_700_000_000.0)
    for t, frame in sorted((f for per in frames.values() for f in per), key=lambda f: f[0]):
        rec.frame(t, frame)
    rec.close()
    return FlightLog.load(path)


@contextlib.contextmanager
def _live(frames: dict[int, list[tuple[float, bytes]]], origin: GeoPoint
          ) -> Iterator[tuple[TeamFrame, FleetTable]]:
    """A live team frame (``global``, about ``origin``) over real links, once each link has
    passed every frame of its vehicle to it."""
    team = load_team(SQUARE)
    team = dataclasses.replace(team, config=dataclasses.replace(
        team.config, team_frame=TeamFrameConfig(mode="global", origin=origin)))
    with contextlib.ExitStack() as stack:
        links, ports = {}, {}
        for vid in frames:
            transport = MavutilTransport("udpin:127.0.0.1:0")
            address = transport.local_address
            assert address is not None
            ports[vid] = address[1]
            links[vid] = stack.enter_context(Link(vid, transport, gcs_heartbeat_period_s=0.0,
                                                  timesync_period_s=0.0))
        profiles = {vid: make_profile("px4", link) for vid, link in links.items()}
        table = FleetTable(tuple(frames), profiles)
        frame = TeamFrame(team, profiles, table)
        for vid in links:
            sock = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
            enc = MavlinkEncoder(system_id=vid, component_id=1)
            last = enc.encode(enc.mav.heartbeat_encode(  # after the rest: all of it was heard
                mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_PX4, CUSTOM_MODE_ENABLED, 7,
                mavlink.MAV_STATE_STANDBY, 3))
            for _, data in [*frames[vid], (0.0, last)]:
                sock.sendto(data, ("127.0.0.1", ports[vid]))
                time.sleep(0.001)
        for link in links.values():
            link.wait_for(lambda t: t.heartbeat is not None and t.heartbeat.custom_mode == 7,
                          timeout_s=5.0, what="every frame")
        yield frame, table


@pytest.mark.parametrize("where", list(FIELDS))
def test_the_log_reader_places_a_vehicle_where_the_live_team_frame_does(
        tmp_path: Path, where: str) -> None:
    """Origins that differ: the log is drawn in NED about vehicle 1's first fix (its GPS
    frame), the live frame about the same point as its configured origin. Each vehicle's
    local origin is the same number in both (one function, the same pairs), and so is
    where it lies in the frame. The positions agree to the wire's resolution: the live
    frame adds the local position along the team frame's axes to the origin, the log
    places each fix as it came (rounded to 1e-7 degrees)."""
    field, origins = FIELDS[where]
    frames = _vehicle_frames(field, origins)
    log = _logged(tmp_path / "team.tlog", frames)
    assert log.origin is not None and log.from_global == (1, 2, 3, 4)
    team_origin = GeoPoint(lat=log.origin[0], lon=log.origin[1], alt=log.origin[2])
    with _live(frames, team_origin) as (frame, table):
        live = table.read(time.monotonic()).p_ned[:, :2]
        offsets = {vid: frame.offset(vid) for vid in frames}
        own = {vid: frame.vehicle_origin(vid) for vid in frames}
        assert frame.origin == team_origin
    lla = {vid: (o.lat, o.lon, o.alt) for vid, o in own.items() if o is not None}
    placed = {vid: geodetic_to_ned(p, log.origin) for vid, p in lla.items()}
    assert log.origin_spread == pytest.approx(
        max(math.dist(a, b) for a in placed.values() for b in placed.values()), abs=1e-9)
    logged = np.array([log.tracks[vid].p_ned[-1, :2] for vid in frames])
    resolution = math.radians(1e-7) * EARTH_RADIUS  # m, north; east is less
    assert np.abs(live - logged).max() < resolution, (live, logged)
    for vid in frames:  # one function on the same pairs: the same numbers, exactly
        assert log.local_origins[vid] == lla[vid]
        assert offsets[vid] == tuple(placed[vid][:2])
