"""One team frame: every vehicle placed in one NED frame about a team origin.

Each real autopilot keeps its own local origin (ArduPilot and PX4 set it at
their first GPS fix), so four LOCAL_POSITION_NED all start at (0, 0) wherever
the vehicles stand. Taken as one frame, the shape-keeping commands of a team
of four ArduCopters scattered it (worst distance error 21.5 m). The guidance
keeps flying on the high-rate LOCAL_POSITION_NED; :class:`TeamFrame` only
tells the fleet table (:meth:`gcs.loop.FleetTable.shift`) where each local
origin lies in the team frame, by the team file's ``team_frame.mode``
(:class:`gcs.config.TeamFrameConfig`):

* ``global``: a vehicle's origin is its GPS_GLOBAL_ORIGIN, or else the median
  over GLOBAL_POSITION_INT beside the LOCAL_POSITION_NED of the same instant
  (taken only while disarmed: in flight the origin stays put). The team origin
  is the config's, or the mean of every vehicle's origin once all are known.
  The geodesy (WGS-84) and these origins are :mod:`gcs.wire`'s, which the log
  reader places a recorded flight's vehicles with too.
  A vehicle without an origin has no position (NaN) and cannot be armed.
* ``set_origin``: the GCS sends every vehicle the config's origin
  (SET_GPS_GLOBAL_ORIGIN) when it is first heard and again before arming, and
  the local frames are then one; a vehicle that answers with another origin
  (ArduPilot takes it only before its origin is set) refuses the arm.
* ``shared``: the local frames are one already (the simulator, one
  motion-capture system).

Only the horizontal is shifted: each vehicle's altitude stays its own, above
its origin (where it stood at boot), which is what its altitude setpoints are
in. The offsets and the team origin are events (in the ``.tlog`` too).
"""

from __future__ import annotations

import contextlib
import functools
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from gcs.config import GeoPoint, Team
from gcs.link import AutopilotProfile, LinkError
from gcs.loop._fleet import FleetTable
from gcs.wire import (
    Heartbeat,
    LocalPosition,
    MavMessage,
    TelemetryRecord,
    geodetic_mean,
    geodetic_median,
    geodetic_to_ned,
    local_origin,
)

__all__ = ["ORIGIN_MOVE_NOTE_M", "PAIR_MAX_DT_S", "TeamFrame"]

PAIR_MAX_DT_S = 0.1
"""Largest gap between a GLOBAL_POSITION_INT and the LOCAL_POSITION_NED it is paired with, s
(vehicle time; the local position is carried over the gap at its velocity)."""

ORIGIN_MOVE_NOTE_M = 0.05
"""A vehicle's place in the team frame is an event again when it moves this much, m (or
comes from another source)."""

_PAIRS = 15
"""GLOBAL/LOCAL pairs whose median is a vehicle's origin."""

_ANSWER_WAIT_S = 2.0
"""Longest wait before arming for the origins asked for, s."""

Note = Callable[[str, str], None]


# -- geodesy (gcs.wire's, on the WGS-84 ellipsoid) ----------------------------------------------

_Lla = tuple[float, float, float]
"""Latitude, longitude (deg) and altitude (m)."""


def _lla(p: GeoPoint) -> _Lla:
    return (p.lat, p.lon, p.alt)


def _point(lla: np.ndarray) -> GeoPoint:
    return GeoPoint(lat=float(lla[0]), lon=float(lla[1]), alt=float(lla[2]))


def _ned(point: GeoPoint, ref: GeoPoint) -> tuple[float, float, float]:
    """``point`` as north, east, down (m) from ``ref``."""
    n, e, d = geodetic_to_ned(_lla(point), _lla(ref))
    return float(n), float(e), float(d)


def _distance(a: GeoPoint, b: GeoPoint) -> float:
    return math.hypot(*_ned(a, b))


def _text(p: GeoPoint) -> str:
    return f"{p.lat:.7f}, {p.lon:.7f}, {p.alt:.2f} m"


# -- per vehicle --------------------------------------------------------------------------------

@dataclass
class _Vehicle:
    """What the frame knows about one vehicle (under the frame's lock)."""

    index: int
    profile: AutopilotProfile
    origin: GeoPoint | None = None
    source: str = ""  # where the origin came from
    reported_at: float = -math.inf  # monotonic time of the latest GPS_GLOBAL_ORIGIN
    local: LocalPosition | None = None
    pairs: deque[_Lla] = field(default_factory=lambda: deque(maxlen=_PAIRS))
    """The origin each recent (fix, local position) pair gives, kept: a new fix adds its
    own, and the median of them is the vehicle's origin (as gcs.wire.local_origin)."""
    armed: bool = False
    heard: bool = False
    placed: tuple[float, float] | None = None  # the offset last announced
    placed_from: str = ""  # and its source

    @property
    def vid(self) -> int:
        return self.profile.link.sysid


class TeamFrame:
    """Ties every vehicle's local frame to the team frame; see the module docstring.

    Args:
        team: the loaded team (``team_frame`` section, links' profiles).
        profiles: autopilot profile per vehicle system id.
        table: the fleet table to shift.
        note: ``note(level, text)`` for events (the runtime's).
    """

    def __init__(self, team: Team, profiles: Mapping[int, AutopilotProfile], table: FleetTable,
                 *, note: Note | None = None) -> None:
        cfg = team.config
        self.config = cfg.team_frame
        self.mode = cfg.team_frame.resolved(link.profile for link in cfg.vehicle_links())
        """``global``, ``set_origin`` or ``shared`` (``auto`` resolved)."""
        self._table = table
        self._note = note if note is not None else (lambda level, text: None)
        self._lock = threading.Lock()
        self._answered = threading.Condition(self._lock)
        self._origin: GeoPoint | None = cfg.team_frame.origin
        self._vehicles = [_Vehicle(i, profiles[vid]) for i, vid in enumerate(table.ids)]
        if self.mode == "shared":
            return
        for v in self._vehicles:
            link = v.profile.link
            link.add_message_listener(functools.partial(self._on_message, v))
            link.add_record_listener(functools.partial(self._on_record, v))
            if self.mode == "global":
                table.shift(v.index, math.nan, math.nan)

    @property
    def origin(self) -> GeoPoint | None:
        """The team origin (None: not known yet, or the frame is ``shared``)."""
        with self._lock:
            return self._origin

    def vehicle_origin(self, vid: int) -> GeoPoint | None:
        """Vehicle ``vid``'s own origin as it last reported it (or as its pairs give it)."""
        with self._lock:
            return self._vehicle(vid).origin

    def offset(self, vid: int) -> tuple[float, float] | None:
        """Where vehicle ``vid``'s local origin lies in the team frame, north and east, m
        (None: unknown); (0, 0) for the shared frames of ``shared`` and ``set_origin``."""
        if self.mode != "global":
            return (0.0, 0.0)
        with self._lock:
            v = self._vehicle(vid)
            return self._offset(v)

    def _vehicle(self, vid: int) -> _Vehicle:
        for v in self._vehicles:
            if v.vid == vid:
                return v
        raise KeyError(f"vehicle {vid} is not in the team")

    # -- receiving (links' receive threads) -----------------------------------------------------

    def _on_message(self, v: _Vehicle, msg: MavMessage) -> None:
        kind = msg.get_type()
        if kind == "GPS_GLOBAL_ORIGIN":
            if msg.latitude == 0 and msg.longitude == 0:
                return  # not set
            origin = GeoPoint(lat=msg.latitude * 1e-7, lon=msg.longitude * 1e-7,
                              alt=msg.altitude * 1e-3)
            with self._lock:
                v.origin, v.source, v.reported_at = origin, "GPS_GLOBAL_ORIGIN", time.monotonic()
                self._answered.notify_all()
            self._update(v)
        elif kind == "GLOBAL_POSITION_INT" and self.mode == "global":
            self._pair(v, msg)
        elif kind == "HEARTBEAT" and self.mode == "set_origin":
            with self._lock:
                first, v.heard = not v.heard, True
            if first:
                self._send_origin(v)

    def _on_record(self, v: _Vehicle, record: TelemetryRecord) -> None:
        if isinstance(record, LocalPosition):
            with self._lock:
                v.local = record
        elif isinstance(record, Heartbeat):
            with self._lock:
                v.armed = record.armed

    def _pair(self, v: _Vehicle, msg: MavMessage) -> None:
        """A GLOBAL_POSITION_INT beside the latest LOCAL_POSITION_NED: one estimate of the
        vehicle's origin (while disarmed, and while it reports no origin of its own)."""
        if msg.lat == 0 and msg.lon == 0:
            return  # no fix
        with self._lock:
            local = v.local
            if local is None or v.armed or v.source == "GPS_GLOBAL_ORIGIN":
                return
            dt = msg.time_boot_ms / 1000.0 - local.time_boot_s
            if abs(dt) > PAIR_MAX_DT_S:
                return
            at = tuple(p + u * dt for p, u in zip(local.p_ned, local.v_ned, strict=True))
        fix = (msg.lat * 1e-7, msg.lon * 1e-7, msg.alt * 1e-3)
        this = local_origin([fix], [at])  # off the lock: this pair's alone, once
        with self._lock:  # this vehicle's messages come one at a time (its link's thread)
            v.pairs.append((float(this[0]), float(this[1]), float(this[2])))
            v.origin = _point(geodetic_median(list(v.pairs)))
            v.source = "GLOBAL_POSITION_INT"
            self._answered.notify_all()
        self._update(v)

    def _update(self, changed: _Vehicle) -> None:
        """Vehicle ``changed`` has a new origin: shift it (global), and every vehicle once the
        team origin is fixed (when the last origin came)."""
        if self.mode != "global":
            return
        notes: list[str] = []
        with self._lock:
            shifted = [changed]
            if self._origin is None:
                origins = [v.origin for v in self._vehicles]
                if any(o is None for o in origins):
                    return
                self._origin = _point(geodetic_mean([_lla(o) for o in origins if o is not None]))
                notes.append(f"team frame: origin {_text(self._origin)}, the mean of the "
                             f"vehicles' own origins")
                shifted = self._vehicles
            for v in shifted:
                offset = self._offset(v)
                if offset is None:
                    continue
                self._table.shift(v.index, *offset)
                if v.placed is None or math.dist(v.placed, offset) >= ORIGIN_MOVE_NOTE_M \
                        or v.placed_from != v.source:
                    v.placed, v.placed_from = offset, v.source
                    notes.append(f"vehicle {v.vid}: local origin {offset[0]:+.2f} m north, "
                                 f"{offset[1]:+.2f} m east in the team frame (from "
                                 f"{v.source})")
        for text in notes:
            self._note("info", text)

    def _offset(self, v: _Vehicle) -> tuple[float, float] | None:
        if v.origin is None or self._origin is None:
            return None
        north, east, _down = _ned(v.origin, self._origin)
        return (north, east)

    def _send_origin(self, v: _Vehicle) -> None:
        """SET_GPS_GLOBAL_ORIGIN with the team origin to vehicle ``v``."""
        origin = self.config.origin
        assert origin is not None  # set_origin mode needs one (TeamFrameConfig)
        link = v.profile.link
        try:
            link.send_message(link.mav.set_gps_global_origin_encode(
                link.sysid, round(origin.lat * 1e7), round(origin.lon * 1e7),
                round(origin.alt * 1e3), int(time.time() * 1e6)))
        except LinkError:
            return  # closed meanwhile

    # -- before arming ------------------------------------------------------------------------

    def problems(self, *, ask: bool = True) -> list[tuple[int, str]]:
        """What keeps a vehicle out of the team frame: (vehicle, one line naming it) each
        (empty: every vehicle placed). Blocks up to a few seconds: ``set_origin`` sends
        the origin again and asks each vehicle for its own, ``global`` asks those whose
        origin is missing. ``ask=False``: from what the vehicles said already, sending
        nothing and never blocking (the checks shown while the team is ready)."""
        if self.mode == "shared":
            return []
        if self.mode == "set_origin":
            return self._check_set_origin(ask=ask)
        with self._lock:
            missing = [v for v in self._vehicles if v.origin is None]
        if missing and ask:
            self._ask_origins(missing, since=-math.inf)
        out = []
        with self._lock:
            for v in self._vehicles:
                if v.origin is None:
                    out.append((v.vid, f"vehicle {v.vid}: no origin of its local frame (neither "
                               f"GPS_GLOBAL_ORIGIN nor GLOBAL_POSITION_INT with a fix): it "
                               f"cannot be placed in the team frame (team_frame: global)"))
        return out

    def _check_set_origin(self, *, ask: bool) -> list[tuple[int, str]]:
        origin = self.config.origin
        assert origin is not None
        since = time.monotonic() if ask else -math.inf
        if ask:
            for v in self._vehicles:
                self._send_origin(v)
            self._ask_origins(self._vehicles, since=since)
        out = []
        with self._lock:
            for v in self._vehicles:
                if v.reported_at < since or v.origin is None:
                    out.append((v.vid, f"vehicle {v.vid}: did not report its origin "
                                       f"(GPS_GLOBAL_ORIGIN) after SET_GPS_GLOBAL_ORIGIN: "
                                       f"origins cannot be checked (team_frame: set_origin)"))
                    continue
                off = _distance(v.origin, origin)
                if off > self.config.origin_tolerance:
                    out.append((v.vid, f"vehicle {v.vid}: its origin {_text(v.origin)} is "
                                       f"{off:.2f} m from the team origin {_text(origin)}: "
                                       f"origins disagree (ArduPilot takes "
                                       f"SET_GPS_GLOBAL_ORIGIN only before its origin is set: "
                                       f"restart it, or use team_frame: global)"))
        return out

    def _ask_origins(self, vehicles: list[_Vehicle], *, since: float) -> None:
        """Ask ``vehicles`` for GPS_GLOBAL_ORIGIN and wait until each reported one after
        ``since`` (monotonic), or :data:`_ANSWER_WAIT_S` passed."""
        for v in vehicles:
            with contextlib.suppress(LinkError):  # refused or unanswered: it may stream it
                v.profile.request_message("GPS_GLOBAL_ORIGIN")
        deadline = time.monotonic() + _ANSWER_WAIT_S
        with self._answered:
            self._answered.wait_for(
                lambda: all(v.reported_at >= since and v.origin is not None
                            for v in vehicles) or time.monotonic() >= deadline,
                timeout=_ANSWER_WAIT_S)
