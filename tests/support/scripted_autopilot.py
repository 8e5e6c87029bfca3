"""A scripted PX4, ArduPilot or simulated autopilot: real pymavlink bytes on UDP loopback.

The autopilot is a thread speaking MAVLink 2 through ``pymavlink.mavutil``,
as a real PX4 or ArduPilot on a UDP port would. It answers commands, streams
HEARTBEAT, LOCAL_POSITION_NED and ATTITUDE_TARGET (a level hover's thrust),
enforces the rules each autopilot imposes (refusing what the real one would
refuse) and records every violation of the expected sequence, which the tests
then require to be empty.

Like a real GPS autopilot it may keep its own local origin (``origin``): its
LOCAL_POSITION_NED is then relative to it, GLOBAL_POSITION_INT (``gps``) gives
the same place on the earth, GPS_GLOBAL_ORIGIN answers REQUEST_MESSAGE and
SET_MESSAGE_INTERVAL (``reports_origin``), and SET_GPS_GLOBAL_ORIGIN is taken
as each autopilot takes it (ArduPilot: only while its origin is not set). It
answers the parameter protocol for its tilt limit (ArduPilot ``ANGLE_MAX`` in
centidegrees, cast into the float field; PX4 ``MPC_TILTMAX_AIR`` in degrees,
integers byte for byte).

The earth is written out here (a local tangent plane on the WGS-84 radii), not
taken from ``gcs``, so a test holds the GCS's geodesy to it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import math
import socket
import struct
import threading
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.config import LinkConfig, Team, TeamFrameConfig, load_team
from gcs.link import Link, LinkManager
from gcs.loop import Action, Event, FleetState, OperatorCommand, Phase, Runtime, WallClock
from gcs.testing import mavlink2_connection
from gcs.transport import MavutilTransport
from gcs.wire import CopterMode, Px4AutoSubMode, Px4MainMode, SigningKey, SimMode
from gcs.wire._modes import px4_custom_mode
from gcs.wire._setpoints import MASK_ACCEL, MASK_ACCEL_XY_POS_Z
from tests.support.paths import ROOT

GCS_SYSID = 245
HOVER_THRUST = 0.4
"""Collective thrust the autopilot reports (ATTITUDE_TARGET), a fraction of its full thrust."""
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
                 position_rate_hz: float = 20.0, flies: bool = False, sysid: int = VEHICLE,
                 xy: tuple[float, float] = (0.0, 0.0), origin: Geo | None = None,
                 gps: bool = False, reports_origin: bool = True,
                 tilt_limit: float | None = None, auto_disarm_s: float | None = None,
                 altitude_wander: float = 0.0) -> None:
        super().__init__(daemon=True, name=f"scripted-{kind}-{sysid}")
        self.kind = kind
        self.sysid = sysid
        self.conn = mavlink2_connection(f"udpout:127.0.0.1:{gcs_port}", source_system=sysid,
                                        source_component=1)
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
        self.xy = xy
        """North and east in its local frame, m."""
        self.origin = origin
        """Its local frame's origin on the earth (None: not set)."""
        self.gps = gps
        """Whether it streams GLOBAL_POSITION_INT (with LOCAL_POSITION_NED, same time stamp)."""
        self.reports_origin = reports_origin
        """Whether it answers for GPS_GLOBAL_ORIGIN (REQUEST_MESSAGE, SET_MESSAGE_INTERVAL)."""
        self.origin_period_s: float | None = None
        self.params: dict[str, list[float]] = {}
        """Name: [value, MAV_PARAM_TYPE] (ArduPilot and PX4)."""
        if kind in TILT_PARAM:
            for name, param_type, default in (TILT_PARAM[kind], EXTRA_PARAM[kind]):
                self.params[name] = [default, param_type]
            if tilt_limit is not None:
                self.params[TILT_PARAM[kind][0]][0] = tilt_limit
        self.param_sets: list[tuple[str, float]] = []
        self.auto_disarm_s = auto_disarm_s
        """ArduPilot: disarm on its own this long after arming without a take-off."""
        self._armed_at: float | None = None
        self.altitude_wander = altitude_wander
        """In the air, the reported altitude off its true one by this much, m, except in
        its own half second of every two (system ids 1-4 by turns: never all four there
        at once), as GPS altitudes wander (PX4 SIH: +-0.15 m)."""

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
        next_beat = next_position = next_origin = 0.0
        last = time.monotonic()
        while not self._quit.is_set():
            now = time.monotonic()
            self._fly(now - last, now)
            last = now
            if self._armed_at is not None and self.auto_disarm_s is not None \
                    and now - self._armed_at > self.auto_disarm_s:
                self.armed, self._armed_at = False, None
            if now >= next_beat:
                self._heartbeat()
                next_beat = now + 0.05
            if self.origin_period_s is not None and now >= next_origin:
                self._send_origin()
                next_origin = now + self.origin_period_s
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
            elif msg.get_type().startswith("PARAM_"):
                self._param(msg)
            elif msg.get_type() == "SET_GPS_GLOBAL_ORIGIN":
                self._set_origin(msg)
            self._check_offboard_stream()

    def _heartbeat(self) -> None:
        base = v20.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (
            v20.MAV_MODE_FLAG_SAFETY_ARMED if self.armed else 0)
        self.conn.mav.heartbeat_send(v20.MAV_TYPE_QUADROTOR, AUTOPILOT[self.kind], base,
                                     self.custom_mode, v20.MAV_STATE_ACTIVE)

    def _position(self) -> None:
        t_ms = int(time.monotonic() * 1000) & 0xFFFFFFFF
        north, east = self.xy
        z = self.z_ned
        if self.altitude_wander and z < 0.0 \
                and int(time.monotonic() * 2.0) % 4 != (self.sysid - 1) % 4:
            z -= self.altitude_wander
        self.conn.mav.local_position_ned_send(t_ms, north, east, z, 0.0, 0.0, self.vz_ned)
        # the collective thrust of a level hover, as PX4 and ArduCopter send it
        self.conn.mav.attitude_target_send(t_ms, 0, (1.0, 0.0, 0.0, 0.0), 0.0, 0.0, 0.0,
                                           HOVER_THRUST)
        if self.gps and self.origin is not None:
            here = moved(self.origin, north, east, z)
            self.conn.mav.global_position_int_send(
                t_ms, round(here.lat * 1e7), round(here.lon * 1e7), round(here.alt * 1000),
                round(-z * 1000), 0, 0, round(self.vz_ned * 100), 0)

    def _send_origin(self) -> None:
        if self.origin is not None:
            self.conn.mav.gps_global_origin_send(round(self.origin.lat * 1e7),
                                                 round(self.origin.lon * 1e7),
                                                 round(self.origin.alt * 1000),
                                                 int(time.time() * 1e6))

    def _set_origin(self, msg: Any) -> None:
        """SET_GPS_GLOBAL_ORIGIN: ArduPilot takes it only while its origin is not set."""
        if msg.target_system != self.sysid:
            self._violation(f"SET_GPS_GLOBAL_ORIGIN for system {msg.target_system}")
            return
        if self.kind == "ardupilot" and self.origin is not None:
            return  # refused without an answer, as ArduPilot's EKF does
        self.origin = Geo(msg.latitude * 1e-7, msg.longitude * 1e-7, msg.altitude * 1e-3)
        self._send_origin()

    def _param(self, msg: Any) -> None:
        """The parameter protocol for the parameters it has."""
        name = msg.param_id if isinstance(msg.param_id, str) else msg.param_id.decode()
        entry = self.params.get(name)
        if entry is None:
            return
        if msg.get_type() == "PARAM_SET":
            if int(msg.param_type) != int(entry[1]):
                self._violation(f"PARAM_SET {name} with type {msg.param_type}")
                return
            entry[0] = from_wire(self.kind, msg.param_value, int(entry[1]))
            self.param_sets.append((name, entry[0]))
        elif msg.get_type() != "PARAM_REQUEST_READ":
            return
        index = list(self.params).index(name)
        self.conn.mav.param_value_send(name.encode(), wire_value(self.kind, *entry),
                                       int(entry[1]), len(self.params), index)

    def _fly(self, dt: float, now: float) -> None:
        """Vertical double integrator driven by afz, as a GUIDED copter given acceleration."""
        if not (self.flies and self.armed and self.custom_mode == CopterMode.GUIDED):
            return
        az = self._afz[1] if self._afz is not None and now - self._afz[0] < 3.0 else 0.0
        self.z_ned += self.vz_ned * dt + 0.5 * az * dt * dt
        self.vz_ned += az * dt

    def _interval(self, msg: Any) -> int:
        """SET_MESSAGE_INTERVAL: LOCAL_POSITION_NED's and GPS_GLOBAL_ORIGIN's rates are
        honoured, the rest accepted."""
        if int(msg.param1) == v20.MAVLINK_MSG_ID_LOCAL_POSITION_NED and msg.param2 > 0:
            self.position_period_s = msg.param2 / 1e6
        if int(msg.param1) == v20.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN and self.reports_origin:
            self.origin_period_s = msg.param2 / 1e6 if msg.param2 > 0 else None
        return v20.MAV_RESULT_ACCEPTED

    def _request(self, msg: Any) -> int:
        """MAV_CMD_REQUEST_MESSAGE: GPS_GLOBAL_ORIGIN when it has one and says so."""
        if int(msg.param1) != v20.MAVLINK_MSG_ID_GPS_GLOBAL_ORIGIN or not self.reports_origin:
            return v20.MAV_RESULT_UNSUPPORTED
        if self.origin is None:
            return v20.MAV_RESULT_FAILED
        self._send_origin()
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
        if msg.command == v20.MAV_CMD_REQUEST_MESSAGE:
            self._ack(msg.command, self._request(msg))
            return
        if msg.command == v20.MAV_CMD_SET_MESSAGE_INTERVAL and self.kind != "sim":
            self._ack(msg.command, self._interval(msg))
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
            self._armed_at = time.monotonic() if self.armed else None
            return v20.MAV_RESULT_ACCEPTED
        if msg.command == TAKEOFF:
            if self.custom_mode != CopterMode.GUIDED or not self.armed:
                self._violation("take-off requested unarmed or outside GUIDED")
                return v20.MAV_RESULT_DENIED
            self.z_ned = -msg.param7
            self._armed_at = None  # flying: no auto-disarm
            return v20.MAV_RESULT_ACCEPTED
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
        elif self.kind == "px4" and self.armed and self._offboard_since is not None:
            self.z_ned = msg.z  # at the streamed altitude at once

    def _check_offboard_stream(self) -> None:
        if self.kind != "px4" or self._offboard_since is None:
            return
        times = [r.t for r in self.setpoints()]
        if len(times) >= 2 and times[-1] - times[-2] > 0.9:  # COM_OF_LOSS_T is 1 s
            self._violation(f"setpoint gap of {times[-1] - times[-2]:.2f} s in OFFBOARD")


# -- the earth, independently of gcs ------------------------------------------------------------

_A, _E2 = 6378137.0, 6.69437999014e-3


@dataclass(frozen=True)
class Geo:
    """Latitude, longitude (degrees) and altitude (m)."""

    lat: float
    lon: float
    alt: float


def _radii(ref: Geo) -> tuple[float, float]:
    """Meridian and prime-vertical radii of curvature at ``ref``, its altitude included, m."""
    s2 = math.sin(math.radians(ref.lat)) ** 2
    return (_A * (1 - _E2) / (1 - _E2 * s2) ** 1.5 + ref.alt,
            _A / math.sqrt(1 - _E2 * s2) + ref.alt)


def moved(ref: Geo, north: float, east: float, down: float = 0.0) -> Geo:
    """The point ``north``, ``east``, ``down`` (m) from ``ref`` (tangent plane: metres)."""
    m, n = _radii(ref)
    return Geo(ref.lat + math.degrees(north / m),
               ref.lon + math.degrees(east / (n * math.cos(math.radians(ref.lat)))),
               ref.alt - down)


def offset(point: Geo, ref: Geo) -> tuple[float, float]:
    """North and east of ``point`` from ``ref``, m (tangent plane)."""
    m, n = _radii(ref)
    return (math.radians(point.lat - ref.lat) * m,
            math.radians(point.lon - ref.lon) * n * math.cos(math.radians(ref.lat)))


# -- parameters -----------------------------------------------------------------------------------

TILT_PARAM = {"ardupilot": ("ANGLE_MAX", v20.MAV_PARAM_TYPE_INT16, 3000.0),
              "px4": ("MPC_TILTMAX_AIR", v20.MAV_PARAM_TYPE_REAL32, 45.0)}
"""Each autopilot's tilt limit: name, type and its default (30 and 45 degrees)."""

EXTRA_PARAM = {"ardupilot": ("DISARM_DELAY", v20.MAV_PARAM_TYPE_INT8, 10.0),
               "px4": ("COM_DISARM_PRFLT", v20.MAV_PARAM_TYPE_INT32, 10.0)}
"""An integer parameter of each (PX4 sends its bytes, not its value)."""

_INT = {v20.MAV_PARAM_TYPE_INT8: "<b", v20.MAV_PARAM_TYPE_INT16: "<h",
        v20.MAV_PARAM_TYPE_INT32: "<i"}


def wire_value(kind: str, value: float, param_type: int) -> float:
    """What goes in PARAM_VALUE's float field for ``value``."""
    fmt = _INT.get(param_type)
    if kind != "px4" or fmt is None:
        return float(value)
    return float(struct.unpack("<f", struct.pack(fmt, int(value)).ljust(4, b"\0"))[0])


def from_wire(kind: str, raw: float, param_type: int) -> float:
    """The value in PARAM_SET's float field."""
    fmt = _INT.get(param_type)
    if kind != "px4" or fmt is None:
        return float(raw)
    return float(struct.unpack(fmt, struct.pack("<f", raw)[:struct.calcsize(fmt)])[0])


def start_peer(link: Link, kind: str, **options: Any) -> ScriptedAutopilot:
    """A scripted autopilot on ``link``'s UDP port, started; returns once the link heard it."""
    assert isinstance(link.transport, MavutilTransport)
    address = link.transport.local_address
    assert address is not None
    peer = ScriptedAutopilot(kind, address[1], sysid=link.sysid, **options)
    peer.start()
    link.wait_for(lambda t: t.heartbeat is not None and t.position is not None,
                  timeout_s=5.0, what="first telemetry")
    return peer


def first_time(records: list[Received]) -> float:
    assert records, "expected at least one message"
    return records[0].t


# -- a team of scripted autopilots and the GCS loop -----------------------------------------------

SQUARE = ROOT / "configs" / "bebop_square.yaml"

REF = Geo(47.397742, 8.545594, 488.0)
"""Where the test teams stand (a field near Zurich, PX4's SITL home)."""


def free_udp_port() -> int:
    (port,) = free_udp_ports(1)
    return port


def free_udp_ports(n: int) -> list[int]:
    """``n`` different UDP ports on 127.0.0.1 that were free a moment ago: held open
    together while chosen (one at a time, the kernel may give a port just released
    again: two vehicles on one port, seen in CI)."""
    with contextlib.ExitStack() as stack:
        socks = [stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
                 for _ in range(n)]
        for sock in socks:
            sock.bind(("127.0.0.1", 0))
        return [int(sock.getsockname()[1]) for sock in socks]


def square_team(profiles: Mapping[int, str], *, team_frame: TeamFrameConfig | None = None,
                **limits: Any) -> Team:
    """The paper's square with a UDP link per vehicle on a free port (the profiles given)."""
    team = load_team(SQUARE)
    ports = free_udp_ports(len(profiles))
    links = tuple(LinkConfig(sysid=vid, transport=f"udpin:127.0.0.1:{port}", profile=profile)
                  for (vid, profile), port in zip(profiles.items(), ports, strict=True))
    cfg = dataclasses.replace(team.config, links=links,
                              team_frame=team_frame or TeamFrameConfig(),
                              limits=dataclasses.replace(team.config.limits, **limits))
    return dataclasses.replace(team, config=cfg)


@dataclass
class Bench:
    """Scripted autopilots behind real links, and the GCS loop over them (not ticking)."""

    team: Team
    manager: LinkManager
    runtime: Runtime
    peers: dict[int, ScriptedAutopilot]

    def ready(self, timeout_s: float = 15.0) -> None:
        """Tick until the loop's pre-flight check passes (phase READY)."""
        deadline = time.monotonic() + timeout_s
        while self.runtime.phase is Phase.CONNECT:
            assert time.monotonic() < deadline, self.runtime.events()
            self.runtime.tick()
            time.sleep(0.05)

    def arm(self, timeout_s: float = 30.0) -> list[Event]:
        """The operator's arm; returns the events it caused, once it ended."""
        before = len(self.runtime.events())
        self.runtime.request(Action.ARM)
        deadline = time.monotonic() + timeout_s
        while self.runtime.action_running:
            assert time.monotonic() < deadline, "the arm did not end"
            time.sleep(0.02)
        return list(self.runtime.events())[before:]


@contextlib.contextmanager
def peer_team(peers: Mapping[int, tuple[str, dict[str, Any]]], *,
              team_frame: TeamFrameConfig | None = None, **limits: Any) -> Iterator[Bench]:
    """The square's four vehicles as scripted autopilots: ``{sysid: (kind, options)}``."""
    team = square_team({vid: kind for vid, (kind, _) in peers.items()}, team_frame=team_frame,
                       **limits)
    clock = WallClock()
    with LinkManager(team.config.vehicle_links(), settings=team.config.gcs, clock=clock.now,
                     check_period_s=0.05) as manager:
        runtime = Runtime(team, manager.profiles, clock,
                          OperatorCommand(team.config.operator, team.config.guidance,
                                          now=clock.now()))
        started: dict[int, ScriptedAutopilot] = {}
        try:
            for vid, (kind, options) in peers.items():
                started[vid] = start_peer(manager.links[vid], kind, **options)
            yield Bench(team, manager, runtime, started)
        finally:
            runtime.close()
            for peer in started.values():
                peer.stop()


def fleet_state(xy: Any, thrust: float, *, modes: tuple[str, ...] = ("GUIDED",) * 4,
                altitude: float = 2.5) -> FleetState:
    """A still, level, armed team at ``xy`` (n, 2) NED, all at ``altitude`` m, every
    vehicle's collective thrust ``thrust``, everything just heard: the loop's view of a
    moment, for its rules."""
    n = len(xy)
    p = np.column_stack((np.asarray(xy, dtype=float), np.full(n, -altitude)))
    return FleetState(t=10.0, ids=tuple(range(1, n + 1)), p_ned=p, v_ned=np.zeros((n, 3)),
                      yaw=np.zeros(n), tilt=np.zeros(n), age=np.zeros(n),
                      heartbeat_age=np.zeros(n), armed=np.ones(n, dtype=bool),
                      battery=np.full(n, 90.0), modes=modes, thrust=np.full(n, thrust),
                      thrust_age=np.zeros(n))
