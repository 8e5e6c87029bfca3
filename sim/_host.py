"""The sim host: one process running the whole team and speaking MAVLink for every vehicle.

Why: the vehicles are coupled through the payload, so physics and the
onboard autopilots of the whole team step together in one loop, while each
vehicle is still a separate MAVLink system to the outside (zenoh, and UDP on
request), exactly like a team of real autopilots.

The loop, per chunk of :data:`CHUNK_S` of sim time:

1. wait until the chunk may run: wall-time pacing (``speed``) and, with
   ``lockstep``, until the GCS's last clock ack is at most one guidance
   period behind; while waiting, inbound events are handled as they arrive
   (a setpoint's echo has already left from the receive thread, see
   :meth:`vehicles.endpoint.VehicleEndpoint.take`);
2. handle every event that arrived (frames, acks), then the control messages
   that came meanwhile (:meth:`SimHost._apply_controls`);
3. step world and autopilots in lockstep (:meth:`sim.World.run`);
4. let every endpoint send what is due, publish the clock, and the ground
   truth every :data:`TRUTH_PERIOD_S`.

Start: the team stands on the ground in its desired shape around the NED
origin, heading 0, the payload on the ground at the centroid
(:mod:`sim._team_layout`). The first chunk runs during construction (it
compiles or loads the numba kernels, which can take a while), so a host is
responsive once constructed and its clock starts at :data:`CHUNK_S`.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import time
from enum import Enum
from pathlib import Path

import numpy as np

from gcs.config import GcsLinkConfig, Team, link_key, seal_key
from gcs.wire import SigningKey, SimTruth, vec3
from sim._config import WorldConfig
from sim._fabric import HostFabric
from sim._faults import ControlAction, parse_control
from sim._inbox import ClockAck, ControlMessage, Inbox, InboxItem, Received, Refusals, Stop
from sim._options import HostOptions
from sim._pacing import Pacer
from sim._priority import BackgroundStepping
from sim._ready_team import build_team
from sim._team_layout import team_layout
from sim._udp import UdpPorts
from vehicles import AutopilotConfig
from vehicles.endpoint import VehicleEndpoint

__all__ = ["ACK_MAX_LEAD_S", "CHUNK_S", "CLOCK_REPUBLISH_S", "LIFT_LAG_S", "TRUTH_PERIOD_S",
           "SimHost", "VehicleStatus"]

_log = logging.getLogger(__name__)

CHUNK_S = 1.0 / 128.0
"""Sim time stepped between two looks at the inbox, s (4 autopilot steps)."""

TRUTH_PERIOD_S = 1.0 / 20.0
"""Sim time between two ground-truth samples, s."""

CLOCK_REPUBLISH_S = 0.1
"""While a lockstep host waits for an ack, it repeats its clock this often (wall s)."""

LIFT_LAG_S = 0.05
"""A paced host this far behind wall time steps at normal CPU priority until it caught up, s."""

ACK_MAX_LEAD_S = 5.0
"""A clock ack further ahead of the sim's time than this is refused, s: a GCS acks only
times it was sent, and a forged ack of t = 1e9 would let a lockstep sim run free."""

_EPS = 1e-9


class VehicleStatus(Enum):
    """Whether a vehicle's link works (control topic: cut, restore, kill)."""

    LIVE = "live"
    CUT = "link cut"
    KILLED = "killed"


class SimHost:
    """World, autopilots, one MAVLink endpoint per vehicle, zenoh and UDP; run with :meth:`run`.

    Construction opens the zenoh session (and the UDP ports), so the host is
    reachable as soon as it returns. Close with :meth:`close`.
    """

    def __init__(self, team: Team, options: HostOptions, *, world_config: WorldConfig,
                 autopilot_config: AutopilotConfig) -> None:
        cfg = team.config
        self._options = options
        self._sysids = tuple(team.formation.ids)
        self._period = 1.0 / cfg.guidance.rate_hz
        signing_keys = self._signing_keys = _signing_keys(team, signing=options.signing)
        self._world, self._autopilot = build_team(
            team_layout(team, ground_z_ned=world_config.ground.z_ned),
            payload_mass=cfg.payload.mass, rng=np.random.default_rng(options.seed),
            airframe=cfg.airframe, world_config=world_config,
            autopilot_config=autopilot_config)
        if options.separate_origins:  # each its own origin where it stands, at the world's level
            for k, (north, east, _) in enumerate(self._world.p_ned):
                self._autopilot.set_origin(k, (north, east, 0.0))
        self._world.run(self._autopilot, CHUNK_S)  # warm-up: compile or load the kernels now
        self._inbox = Inbox()
        self._refusals = Refusals()
        self._signature_refused = [0] * len(self._sysids)
        self._next_signature_check = 0.0
        self._status = [VehicleStatus.LIVE] * len(self._sysids)
        self._cut_until: dict[int, float] = {}  # vehicle index -> sim time its timed cut ends
        self._wind_mean = self._world.params.wind_mean.copy()  # the world config's
        self._gust_std = world_config.wind.gust_std
        self._gusts: list[tuple[float, np.ndarray]] = []  # (sim time it ends, wind it adds)
        self._controls: list[bytes] = []  # control messages to act on at the next chunk
        self._pacer = Pacer(options.speed)
        # lockstep: nothing past the first chunk runs before a GCS acks its first tick, so
        # what the GCS sees does not depend on when it connected
        self._acked = -math.inf
        self._stopping = False
        self._next_truth = 0.0
        self._udp: UdpPorts | None = None
        self._receiving = False  # set once constructed: earlier frames are dropped, as at boot
        measurements = self._world.measurements()
        self._endpoints = [  # before any receiver: frames may arrive at once
            VehicleEndpoint(self._autopilot, k, sysid=sysid, measurements=measurements,
                            send=functools.partial(self._send, k),
                            signing_key=signing_keys.get(sysid),
                            reference=world_config.home.geodetic)
            for k, sysid in enumerate(self._sysids)]
        self._fabric = HostFabric(options.zenoh_settings(),
                                  fleet=options.fleet or cfg.gcs.fleet, sysids=self._sysids,
                                  inbox=self._inbox, on_frame=self._receive,
                                  announce_sent=options.lockstep, refusals=self._refusals,
                                  seal_key=seal_key(_signing_settings(team, options.signing),
                                                    Path(team.source).parent))
        try:
            if options.udp:
                self._udp = UdpPorts(len(self._sysids), base_port=options.udp_base_port,
                                     gcs_port=options.udp_gcs_port, on_datagram=self._receive)
        except BaseException:
            self._fabric.close()
            raise
        self._receiving = True

    # -- facts ----------------------------------------------------------------------------------

    @property
    def t(self) -> float:
        """Sim time, s."""
        return self._world.t

    @property
    def fleet(self) -> str:
        """Fleet name in the zenoh keys."""
        return self._fabric.fleet

    def ready_line(self) -> str:
        """One line naming every endpoint, printed when the host is reachable."""
        zenoh = self._fabric.settings
        parts = [f"fleet {self.fleet}", f"{len(self._sysids)} vehicles",
                 f"zenoh listen {' '.join(zenoh.listen) or 'none'}"]
        if zenoh.connect:
            parts.append(f"connect {' '.join(zenoh.connect)}")
        speed = self._pacer.speed
        parts.append("speed max" if speed is None else f"speed {speed:g}x")
        if self._options.lockstep:
            parts.append(f"lockstep {self._period:g} s")
        elif self._options.background:
            parts.append("background")
        if self._options.separate_origins:
            parts.append("separate origins")
        if self._gust_std > 0.0:
            parts.append(f"gusts {self._gust_std:g} m/s")
        if not self._signing_keys:
            parts.append("UNSIGNED (--insecure: anyone who reaches a port commands the vehicles)")
        if self._udp is not None:
            ports = " ".join(f"{s}=127.0.0.1:{p}" for s, p in zip(self._sysids, self._udp.ports,
                                                                   strict=True))
            gcs = self._udp.gcs_port
            parts.append(f"udp {ports}" + (f" -> gcs 127.0.0.1:{gcs}" if gcs else ""))
        return "sim ready: " + ", ".join(parts)

    # -- running --------------------------------------------------------------------------------

    def stop(self) -> None:
        """Ask :meth:`run` to return after the current chunk; safe from signal handlers."""
        self._inbox.put(Stop())

    def run(self) -> None:
        """Step until :meth:`stop`, or the first chunk boundary at or after the duration; blocks."""
        # A lockstep host is what the GCS waits for at every tick: never in the background.
        priority = BackgroundStepping(lag_s=LIFT_LAG_S) \
            if self._options.background and not self._options.lockstep else None
        if priority is not None and not priority.start():
            _log.warning("--background: this process may not raise a thread's priority again "
                         "(root or CAP_SYS_NICE needed) or its watchdog process did not start, "
                         "so the loop steps at normal priority")
        try:
            self._step_until_stopped(priority)
        finally:
            if priority is not None:
                priority.close()
                if priority.lifts:
                    _log.info("fell behind wall time %d times (stepped at normal priority "
                              "until caught up)", priority.lifts)

    def _step_until_stopped(self, priority: BackgroundStepping | None) -> None:
        duration = self._options.duration
        self._fabric.publish_clock(self.t)
        while not self._stopping:
            if duration is not None and self.t >= duration - _EPS:
                break
            target = self.t + CHUNK_S
            self._wait_until_due(target, priority)
            if self._stopping:
                break
            self._drain()
            self._apply_controls()
            self._end_timed_faults()
            self._world.run(self._autopilot, CHUNK_S)
            self._after_chunk()

    @property
    def refusals(self) -> dict[str, int]:
        """Inputs refused so far by kind (oversize payloads, malformed control messages and
        acks), beside what each endpoint's decoder counts."""
        return self._refusals.counts()

    def close(self) -> None:
        """Log each vehicle's link counters, then close zenoh and UDP; idempotent."""
        for k, endpoint in enumerate(self._endpoints):
            c = endpoint.counters()
            _log.info("vehicle %d: %d frames, %d garbage bytes, %d dropped (%d refused by "
                      "signing), %d not for it, %d oversize payloads, %d setpoints (%d refused), "
                      "%d commands",
                      endpoint.sysid, c.decode.frames, c.decode.garbage_bytes, c.decode.dropped,
                      c.decode.refused_signature, c.not_for_us, self._fabric.oversize(k),
                      c.setpoints_accepted + c.setpoints_refused, c.setpoints_refused,
                      c.commands)
        summary = self._refusals.summary()
        if summary:
            _log.info("refused inputs: %s", summary)
        self._fabric.close()
        if self._udp is not None:
            self._udp.close()

    def _wait_until_due(self, target: float, priority: BackgroundStepping | None) -> None:
        """Handle events until ``target`` may be simulated (pacing and lockstep allow it)."""
        while not self._stopping:
            if self._options.lockstep and target > self._acked + self._period + _EPS:
                if not self._handle(self._inbox.get(CLOCK_REPUBLISH_S)):
                    self._fabric.publish_clock(self.t)  # for a GCS that joined late
                continue
            deadline = self._pacer.deadline(target)
            if priority is not None:
                priority.set_due(deadline)
            wait = 0.0 if deadline is None else deadline - time.monotonic()
            if wait <= 0.0:
                return
            if priority is not None:
                priority.keeping_up()
            self._handle(self._inbox.get(wait))

    def _after_chunk(self) -> None:
        t = self.t
        for k, endpoint in enumerate(self._endpoints):
            if self._status[k] is not VehicleStatus.KILLED:
                endpoint.update(t)
                self._drain()  # keep command acks prompt while telemetry goes out
        if t >= self._next_truth - _EPS:
            self._next_truth += TRUTH_PERIOD_S  # keeps the 20 Hz phase between chunk times
            if self._next_truth <= t:
                self._next_truth = t + TRUTH_PERIOD_S
            self._fabric.publish_truth(self._truth())
        if t >= self._next_signature_check - _EPS:  # once a second: not on every chunk
            self._next_signature_check = t + 1.0
            self._note_signature_refusals()
        self._fabric.publish_clock(t)  # last: a lockstep sample counts what went before

    def _note_signature_refusals(self) -> None:
        """Frames a vehicle refused by signing, as refused inputs (logged, counted)."""
        for k, endpoint in enumerate(self._endpoints):
            refused = endpoint.counters().decode.refused_signature
            new = refused - self._signature_refused[k]
            if new > 0:
                self._signature_refused[k] = refused
                self._refusals.refuse("MAVLink frame", f"vehicle {endpoint.sysid}: {new} not "
                                      f"signed with the team key (unsigned, another key, or "
                                      f"replayed)", count=new)

    def _truth(self) -> SimTruth:
        w = self._world
        return SimTruth(
            t=w.t, ids=self._sysids,
            vehicle_p_ned=tuple(vec3(p) for p in w.p_ned),
            payload_p_ned=vec3(w.payload_p_ned), payload_v_ned=vec3(w.payload_v_ned),
            rope_tension=tuple(float(x) for x in w.rope_tension))

    # -- events ---------------------------------------------------------------------------------

    def _drain(self) -> None:
        """Handle every event already waiting, without waiting for more."""
        while self._handle(self._inbox.get(0.0)):
            pass

    def _handle(self, event: InboxItem | None) -> bool:
        """Act on one event; False if there was none."""
        if event is None:
            return False
        if isinstance(event, Received):
            if self._status[event.index] is VehicleStatus.LIVE:
                self._endpoints[event.index].apply(event.inbound, self.t)
        elif isinstance(event, ClockAck):
            partner = self._fabric.partner
            if event.t > self.t + ACK_MAX_LEAD_S:  # a GCS acks times it was sent
                self._refusals.refuse("clock ack", f"for t = {event.t:g} s, far ahead of the "
                                                   f"sim's {self.t:g} s")
            elif partner is not None and event.partner != partner:
                # one partner: on two GCSs' acks the sim would run on the later one's ticks
                self._refusals.refuse("clock ack", f"from a second GCS (partner "
                                      f"{event.partner:08x}; following {partner:08x})")
            else:
                if partner is None and self._options.lockstep:
                    self._fabric.partner = event.partner  # named on the clock from now on
                    _log.info("in lockstep with GCS %08x from t = %.3f s", event.partner,
                              self.t)
                self._acked = max(self._acked, event.t)
        elif isinstance(event, ControlMessage):
            self._controls.append(event.data)
        else:
            self._stopping = True
        return True

    def _apply_controls(self) -> None:
        """Act on the control messages that came since the last chunk, at its boundary.

        Why not as they arrive: a control message and a tick's setpoints travel on
        different keys, so a cut acted on at once would fall now ahead of the cut
        vehicle's setpoint of that tick (dropped: that vehicle flies the tick before's),
        now behind it, as the threads happen to run, and two lockstep runs of one seed
        would differ from there. At the chunk boundary every frame the GCS sent before
        its ack is in (it acks once the sim echoed the tick's setpoints).
        """
        controls, self._controls = self._controls, []
        for data in controls:
            self._control(data)

    def _control(self, data: bytes) -> None:
        try:
            command = parse_control(data)
        except ValueError as exc:
            self._refusals.refuse("control message", str(exc))
            return
        if command.action is ControlAction.GUST:
            assert command.wind_ned is not None and command.seconds is not None
            self._gusts.append((self.t + command.seconds, np.array(command.wind_ned)))
            self._set_wind()
            _log.info("gust of %s m/s (NED) for %g s at t = %.3f s", command.wind_ned,
                      command.seconds, self.t)
            return
        if command.sysid not in self._sysids:
            self._refusals.refuse("control message", f"no vehicle {str(command.sysid)[:40]}")
            return
        k = self._sysids.index(command.sysid)
        status = self._status[k]
        if status is VehicleStatus.KILLED:
            self._refusals.refuse("control message", f"vehicle {command.sysid} is dead")
            return
        self._status[k] = _NEXT_STATUS[command.action]
        self._cut_until.pop(k, None)
        if command.action is ControlAction.CUT and command.seconds is not None:
            self._cut_until[k] = self.t + command.seconds
        if command.action is ControlAction.KILL:
            self._fabric.drop_vehicle(k)
            self._autopilot.disarm(k, force=True)
        _log.info("vehicle %d %s at t = %.3f s", command.sysid, command.action.text, self.t)

    def _end_timed_faults(self) -> None:
        """End the timed cuts and gusts whose time is up: at a chunk boundary of sim time,
        so a lockstep run ends them at the same instant every time."""
        t = self.t
        for k, end in list(self._cut_until.items()):
            if t >= end - _EPS:
                del self._cut_until[k]
                self._status[k] = VehicleStatus.LIVE
                _log.info("vehicle %d restored at t = %.3f s (timed cut)", self._sysids[k], t)
        if any(t >= end - _EPS for end, _ in self._gusts):
            self._gusts = [(end, wind) for end, wind in self._gusts if t < end - _EPS]
            self._set_wind()
            _log.info("gust over at t = %.3f s", t)

    def _set_wind(self) -> None:
        """The world's mean wind: the configured one plus every gust blowing (the physics
        kernel reads the array in place)."""
        wind = self._wind_mean.copy()
        for _, extra in self._gusts:
            wind += extra
        self._world.params.wind_mean[:] = wind

    def _receive(self, index: int, data: bytes, peer: tuple[str, int] | None = None) -> None:
        """A payload for vehicle ``index`` (receive threads): echo now, the rest to the loop."""
        if not self._receiving or self._status[index] is not VehicleStatus.LIVE:
            return
        if peer is not None and self._udp is not None:
            self._udp.learn(index, peer)  # before the echo, which goes to learned peers
        self._endpoints[index].take(
            data, self._world.t, lambda inbound: self._inbox.put(Received(index, inbound)))

    def _send(self, index: int, frame: bytes) -> None:
        if self._status[index] is not VehicleStatus.LIVE:
            return
        self._fabric.send_frame(index, frame)
        if self._udp is not None:
            self._udp.send(index, frame)


_NEXT_STATUS = {
    ControlAction.KILL: VehicleStatus.KILLED,
    ControlAction.CUT: VehicleStatus.CUT,
    ControlAction.RESTORE: VehicleStatus.LIVE,
}


def _signing_settings(team: Team, signing: bool) -> GcsLinkConfig:
    """The team file's signing settings, with signing off if ``--insecure`` says so."""
    settings = team.config.gcs
    return settings if signing else dataclasses.replace(settings, signing=False)


def _signing_keys(team: Team, *, signing: bool) -> dict[int, SigningKey]:
    """Each vehicle's signing key: the key file its link names, else the team key
    (every simulated vehicle is signed unless ``signing`` or the team file says not)."""
    base = Path(team.source).parent
    settings = _signing_settings(team, signing)
    out: dict[int, SigningKey] = {}
    for link in team.config.vehicle_links():
        key = link_key(dataclasses.replace(link, profile="sim"), settings=settings,
                       base_dir=base)
        if key is not None:
            out[link.sysid] = key
    return out


