"""The GCS loop: operator sticks in, one acceleration setpoint per vehicle out, at 4 Hz.

Each tick (scheduled on a :class:`~gcs.loop.Clock`, wall or simulator time):

1. read the fleet's latest telemetry (:class:`gcs.loop.FleetTable`);
2. apply the safety rules (:func:`gcs.loop._safety.evaluate`): freeze the motion,
   hold a deformed team (each vehicle on its own point) or land the team; re-engage
   vehicles that dropped to hold on a setpoint gap (:mod:`gcs.loop._recovery`);
3. take the operator's command, limit it at the geofence
   (:mod:`gcs.loop._geofence`), run the guidance (relative positions, own
   velocities), saturate, and send each vehicle its setpoint through its
   autopilot profile; an error about one vehicle is reported and the loop
   goes on;
4. advance the flight phase and record the guidance internals.

Between ticks the latest setpoints are re-sent (``guidance.setpoint_rate_hz``,
12 Hz by default) by a thread of their own with its own wall-clock deadline:
the guidance stays at the paper's 4 Hz, and a tick that comes late (a busy
machine, a slow page, a garbage collection) no longer leaves a vehicle half a
second without a setpoint, which sends it into hold. A setpoint re-sent more
than :data:`HELD_SETPOINT_S` after its tick is replaced by velocity damping
(the tick's shape-keeping terms are out of date by then). In lockstep with the
simulator (``gcs fly``) the sim cannot outrun the loop, and re-sends would
arrive at sim times that vary from run to run, so there each tick sends once.

Phase actions that wait for acknowledgements (arm, take off, land) run on a
worker thread, so the loop never waits on a vehicle. The latest
:class:`RuntimeSnapshot` is what the UI and the flight metrics read.
"""

from __future__ import annotations

import collections
import functools
import math
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from gcs.analysis import Analysis, NoHangingPointError, a_safe_span, analyze, desired_load
from gcs.common import HOLD_KP, HOLD_KV
from gcs.config import Team
from gcs.formation import fit_rotation
from gcs.guidance import (
    Guidance,
    MotionDemand,
    finite_max_norm,
    rope_growth_lead,
    rope_pull_ned,
    rope_turn_lead,
    saturate,
)
from gcs.link import AutopilotProfile, Fanout, LinkError
from gcs.loop._clock import Clock, ClockStoppedError
from gcs.loop._deformation import Deformation, DeformationPolicy
from gcs.loop._fleet import FleetState, FleetTable
from gcs.loop._geofence import FenceVerdict, fence_demand
from gcs.loop._load_share import LoadSharing
from gcs.loop._operator import OperatorCommand, OperatorSnapshot
from gcs.loop._phases import Action, Phase, PhaseError, next_phase
from gcs.loop._prearm import Prearm, PrearmError
from gcs.loop._reached import AltitudeReached
from gcs.loop._recovery import Recovery
from gcs.loop._safety import SafetyVerdict, evaluate
from gcs.loop._stepgate import HOLD_CAP_S, StepGate
from gcs.loop._team_frame import TeamFrame
from gcs.wire import SETPOINT_MESSAGE, SetpointPacker, SimTruth, StatusText, TelemetryRecord

__all__ = ["HELD_SETPOINT_S", "HOLD_KP", "HOLD_KV", "LINK_DELAY_CAP_S", "Event",
           "FlightRecorder", "Runtime", "RuntimeSnapshot", "TickStats"]

LINK_DELAY_CAP_S = 0.25
"""Largest round trip the guidance's prediction horizon follows, s: beyond it no lead saves
the paper's gains at 4 Hz (tests/guidance/test_link_delay.py)."""

ROPE_LEAD_CARRIED_MIN = 0.5
"""Least share of the payload's weight the thrusts must show on the ropes for the spin's rope
lead to act (carried, it is near 1; on copters without a payload, 0.0)."""

COMING_DOWN_DROP_M = 0.5
"""How far below the team's median altitude a vehicle out of its streaming mode counts as
coming down on its own, m (the load-sharing trims move a vehicle a few cm)."""

HELD_SETPOINT_S = 1.0
"""Longest a tick's acceleration setpoint is re-sent, s of the loop's clock; past it, a late
loop's re-sends damp velocity only."""


class FlightRecorder(Protocol):
    """Where the loop records a flight: :class:`gcs.flightlog.TlogRecorder` writes a ``.tlog``.

    The loop sees only this, so the flight log (which reads the loop's phases
    and snapshots back) sits above the loop.
    """

    def frame(self, t: float, frame: bytes) -> None:
        """Record one MAVLink frame, in or out."""

    def text(self, t: float, text: str, *, severity: int) -> None:
        """Record a phase change or a warning."""

    def team(self, t: float, *, ids: tuple[int, ...], edges: np.ndarray, distances: np.ndarray,
             accel_norm: float, accel_axis: float) -> None:
        """Record the team, once, before the first tick."""

    def internals(self, t: float, *, arrays: dict[str, np.ndarray],
                  sticks: tuple[float, float, float], scale: float, altitude: float,
                  phase: int) -> None:
        """Record one tick of guidance internals."""


@dataclass(frozen=True)
class Event:
    """Something the operator should see: a phase change, a warning, an error."""

    t: float
    level: str  # "info", "warning", "error"
    text: str


@dataclass(frozen=True)
class TickStats:
    """Timing of the loop over the recent ticks, s."""

    ticks: int
    compute_last: float
    compute_p99: float
    jitter_p99: float
    overruns: int
    stall_max: float = 0.0  # how late the latest tick so far came, s
    setpoint_gap_max: float = 0.0  # longest time between two setpoint rounds (loop's clock), s


@dataclass(frozen=True, eq=False)
class RuntimeSnapshot:
    """The state of one tick, for the UI and the metrics (immutable; latest wins)."""

    fleet: FleetState
    phase: Phase
    operator: OperatorSnapshot
    demand: MotionDemand  # what the guidance used (frozen motion: zero sticks)
    accel_cmd: np.ndarray  # (n, 2) NED m/s^2 sent this tick (zeros when not streaming)
    distance_errors: np.ndarray  # (m,) m, NaN while unknown
    safety: SafetyVerdict
    compute_time: float  # s of wall time, this tick (Runtime.stats() has the percentiles)
    compute_cpu: float = 0.0  # s of this thread's CPU time, this tick (excludes preemption)
    events: tuple[Event, ...] = field(default=())
    truth: SimTruth | None = None  # simulation only: the ground truth of this tick
    moving: bool = False  # the operator's motion was flown this tick (not frozen or held)
    fence: FenceVerdict | None = None  # what the geofence did (None: not applied)
    recovery: str = ""  # vehicles waiting to be re-engaged, and when (empty: none)
    shape: Deformation = Deformation.NONE  # what a team deformed beyond the bound does
    prearm: tuple[str, ...] = ()  # ready: the checks before arming failing now (Prearm.watch)


_GAP_S = 0.3
"""Time without a setpoint round after which the vehicles may have dropped to hold, s of the
loop's clock (their timeout is 0.5 s: the stream may have stopped before the loop noticed)."""

_ON_GCS_SETPOINTS = frozenset({Phase.HOVER, Phase.LIFTING, Phase.FORMATION,
                               Phase.SETTING_DOWN})
"""Phases in which every vehicle must stay in the mode that flies the GCS's setpoints."""

_CARRYING = frozenset({Phase.LIFTING, Phase.FORMATION, Phase.SETTING_DOWN})
"""Phases in which the payload may hang from the ropes (load sharing acts in them)."""
_SLACK_HOVER = frozenset({Phase.HOVER, Phase.LIFTING, Phase.FORMATION})
"""Phases whose thrusts below the taut-rope altitude are each vehicle's own weight (not
the take-off's or the landing's climb and descent)."""
_SHARE_DT_MAX = 0.5
"""Longest step of the load-sharing trims, s: a late tick does not jump them."""


class Runtime:
    """The formation loop of one team.

    Args:
        team: the loaded team.
        profiles: autopilot profile per vehicle system id (from the LinkManager).
        clock: where time comes from.
        operator: the operator command the sources write to.
        recorder: optional flight recorder.
        analysis: the team's worst-case analysis (computed if not given).
        truth_source: in simulation, gives the latest ground truth to record.
        setpoints_per_tick: setpoints per vehicle and tick (default: from the
            config's ``guidance.setpoint_rate_hz``; 1 sends only the tick's own).
    """

    def __init__(self, team: Team, profiles: Mapping[int, AutopilotProfile], clock: Clock,
                 operator: OperatorCommand, *, recorder: FlightRecorder | None = None,
                 analysis: Analysis | None = None,
                 truth_source: Callable[[], SimTruth | None] | None = None,
                 setpoints_per_tick: int | None = None, gate: StepGate | None = None) -> None:
        self.team = team
        self.ids = team.formation.ids
        missing = [vid for vid in self.ids if vid not in profiles]
        if missing:
            raise ValueError(f"no link configured for vehicle(s) {missing}")
        self.profiles = profiles
        self._profile_list = [profiles[vid] for vid in self.ids]
        # one call per tick and vehicle only where the vertical channel is not z itself
        self._vertical_calls = [(i, p.vertical_setpoint)
                                for i, p in enumerate(self._profile_list) if not p.vertical_is_z]
        links = [p.link for p in self._profile_list]
        targets = np.array([(link.sysid, link.target_component) for link in links]).reshape(-1, 2)
        self._packer = SetpointPacker(
            target_system=targets[:, 0], target_component=targets[:, 1],
            kind=np.array([p.setpoint_kind.type_mask for p in self._profile_list]),
            boot_time=np.array([link.boot_time for link in links]))
        self._fanout = Fanout(links)
        self.fleet_table = FleetTable(self.ids, profiles)
        """The team's latest telemetry, kept current by the links (the UI reads it too)."""
        self.clock = clock
        self.operator = operator
        self.recorder = recorder
        self.truth_source = truth_source
        self.guidance = Guidance.from_team(team)
        self.analysis: Analysis = analysis if analysis is not None else analyze(team)
        self.analysis_override = False
        """Fly although the analysis fails (``--override-analysis``): the user's call."""
        self._accel_last = 0.0
        self.period = 1.0 / team.config.guidance.rate_hz
        self._streaming_modes = tuple(p.streaming_mode for p in self._profile_list)
        self._landing_modes = tuple(p.landing_modes for p in self._profile_list)
        # Load the tick's compiled kernels now, on the arrays the tick passes them (as the
        # guidance does): compiling or loading them at the first tick made it late.
        fleet = self.fleet_table.read(0.0)
        _ = fleet.located
        evaluate(team.config.safety, self.ids, fleet.age, fleet.p_ned, safe_radius=1.0)
        team.formation.distance_errors(fleet.p_ned[:, :2])
        finite_max_norm(np.zeros((fleet.n, 2)))
        self.setpoints_per_tick = (team.config.guidance.setpoints_per_tick
                                   if setpoints_per_tick is None else setpoints_per_tick)
        if self.setpoints_per_tick < 1:
            raise ValueError(f"setpoints_per_tick must be at least 1, got {setpoints_per_tick}")
        self._streamed: np.ndarray | None = None  # (n, 2) the last tick's setpoints, if streaming
        self._streamed_at = 0.0  # the loop's time of that tick
        self._send_lock = threading.Lock()  # the loop and the re-send thread share the packer
        self._last_send = -math.inf  # wall time of the last setpoint round (-inf: none)
        self._last_send_clock = -math.inf  # the same on the loop's clock
        self._gap_max = 0.0
        self._gap_seen = False  # a setpoint round came later than _GAP_S after the one before
        self._stall_max = 0.0
        safety = team.config.safety
        self.recovery = Recovery(automatic=safety.recovery == "auto",
                                 settle=safety.recover_after)
        """Re-engages vehicles that dropped to hold on a setpoint gap."""
        for profile in self._profile_list:  # a vehicle saying its setpoints stopped
            profile.link.add_record_listener(self._on_record)
        self.deformation = DeformationPolicy(growth=safety.deformed_land_growth)
        """Hold, re-form or land a team deformed beyond the safe bound."""
        self._shape = Deformation.NONE
        self._rtts: collections.deque[float] = collections.deque(maxlen=40)
        self._base_lead = self.guidance.lead
        self._fence_text = ""
        self._handing_over = False  # taking off: the vehicles are switching to offboard
        self.resends = 0
        """Setpoint rounds re-sent between ticks so far."""
        self._phase = Phase.CONNECT
        self._lock = threading.Lock()
        self._events: collections.deque[Event] = collections.deque(maxlen=200)
        self._active_warnings: set[tuple[str, int]] = set()
        self._latched: set[tuple[str, int]] = set()  # _warn_once's, until _unlatch
        self._reached = AltitudeReached()  # the lift's or the set-down's altitude
        self._reached_in: Phase | None = None
        self._modes: dict[int, str] = {}
        self._modes_seen: tuple[str, ...] | None = None
        self.errors = 0
        """Error events so far (the event list keeps only the recent ones)."""
        self.gate = gate if gate is not None else StepGate(enabled=False)
        """Lets phase actions act only at ticks in lockstep (disabled otherwise)."""
        self.follow_link_delay = not self.gate.enabled and self._base_lead > 0.0
        """Lengthen the guidance's prediction by the links' round trip (not in lockstep,
        where the simulator waits for the setpoints: no delay, and a wall-time figure
        would make runs differ)."""
        # An action and its step per vehicle, twice: the loop may start a landing while an
        # action is stuck. Fewer and a vehicle's step would queue behind the others (in
        # lockstep, holding every tick's window until the gate's cap).
        self._pool = ThreadPoolExecutor(max_workers=2 * (len(self.ids) + 1),
                                        thread_name_prefix="gcs-action")
        self._action_busy = threading.Lock()
        self._abort_at: float | None = None
        self._compute: collections.deque[float] = collections.deque(maxlen=400)
        self._jitter: collections.deque[float] = collections.deque(maxlen=400)
        self._overruns = 0
        self._ticks = 0
        self._snapshot: RuntimeSnapshot | None = None
        self._listeners: list[Callable[[RuntimeSnapshot], None]] = []
        if recorder is not None:
            f, lim = team.formation, team.config.limits
            recorder.team(clock.now(), ids=f.ids, edges=f.edges, distances=f.distances,
                          accel_norm=lim.accel_norm, accel_axis=lim.accel_axis)
            for vid in self.ids:
                profiles[vid].link.add_frame_listener(
                    lambda _direction, frame: recorder.frame(self.clock.now(), frame))
        self.team_frame = TeamFrame(team, profiles, self.fleet_table, note=self.note)
        """Where each vehicle's local frame lies in the team frame the fleet table reads in."""
        self.prearm = Prearm(team, self.analysis, self.team_frame, profiles, note=self.note)
        """The checks an arm must pass."""
        self._rope_pull: tuple[float, np.ndarray] | None = None  # scale, (n, 2) body-frame pulls
        self.load_sharing = _load_sharing(team)
        """The altitude trims that keep the payload's split as designed (None: off, or a
        team with no free split: three vehicles)."""
        self._shared_at = -math.inf

    # -- state ---------------------------------------------------------------------------

    @property
    def phase(self) -> Phase:
        with self._lock:
            return self._phase

    @property
    def snapshot(self) -> RuntimeSnapshot | None:
        """The latest tick's snapshot (None before the first tick)."""
        return self._snapshot

    def events(self) -> tuple[Event, ...]:
        """Recent events, oldest first."""
        with self._lock:
            return tuple(self._events)

    def add_listener(self, callback: Callable[[RuntimeSnapshot], None]) -> None:
        """Call ``callback(snapshot)`` after every tick (on the loop thread: keep it short)."""
        self._listeners.append(callback)

    @property
    def action_running(self) -> bool:
        """Whether a phase action (arm, take off, land, resume...) is still running."""
        return self._action_busy.locked()

    def safe_radius_for(self, accel: float) -> float:
        """Largest vehicle-to-centroid distance at which ``accel`` (m/s^2) is still available.

        The analysis' safe deformation is this bound at the largest acceleration
        the guidance may command; the loop applies it to the acceleration it does
        command (the larger of the last tick's and a floor of a quarter of the
        limit), so a gently flown team may deform more before its motion freezes.
        """
        a = self.analysis
        cfg = self.team.config
        demand = max(accel, 0.25 * cfg.limits.accel_norm)
        return 0.5 * a_safe_span(a.horizontal_force, cfg.airframe.mass, demand,
                                 a.rope_pull_bound, cfg.payload.rope_length)

    def taut_altitude(self, scale: float) -> float:
        """Vehicle altitude at which the first rope becomes taut with the payload on the
        ground, m (:meth:`gcs.config.Team.taut_altitude`: each rope its own length)."""
        return self.team.taut_altitude(scale)

    def note(self, level: str, text: str) -> None:
        """Add an event from outside the loop (link presence, UI, gamepad): shown and logged."""
        if level not in ("info", "warning", "error"):
            raise ValueError(f"event level must be info, warning or error, got {level!r}")
        self._event(level, text)

    def _event(self, level: str, text: str) -> None:
        t = self.clock.now()
        with self._lock:
            self._events.append(Event(t, level, text))
            if level == "error":
                self.errors += 1
        if self.recorder is not None:
            severity = {"info": 6, "warning": 4, "error": 3}[level]
            self.recorder.text(t, text, severity=severity)

    def _set_phase(self, phase: Phase) -> None:
        with self._lock:
            if phase is self._phase:
                return
            self._phase = phase
        self._announce(phase)

    def _announce(self, phase: Phase) -> None:
        """The event of a phase change (what the page's events and the tests look for)."""
        self._event("info", f"phase: {phase.text}")

    # -- operator actions ----------------------------------------------------------------

    def request(self, action: Action) -> None:
        """Start a phase action; returns at once. PhaseError if the phase does not allow it."""
        if action is Action.ABORT:
            self._abort()
            return
        with self._lock:
            target = next_phase(self._phase, action)
        if action in (Action.LIFT, Action.SET_DOWN):
            # target altitude first: a tick between the two would find the old one
            # reached and end the phase at once
            scale = self.operator.snapshot(self.clock.now()).demand.scale
            base = self.taut_altitude(scale)
            flight = self.team.config.flight
            height = base + (flight.lift_height if action is Action.LIFT
                             else -flight.takeoff_slack)
            below, above = flight.pickup_band
            self.operator.set_altitude(height, now=self.clock.now(), rate=flight.lift_rate,
                                       slow=(base - below, base + above, flight.pickup_rate))
            self._set_phase(target)
            return
        if not self._action_busy.acquire(blocking=False):
            raise PhaseError(f"cannot {action.text}: another action is still running")
        self.gate.submit(self._pool, self._run_action, action, target)

    def _abort(self) -> None:
        """Freeze the motion and start the hold, unless already aborting or landing.

        The phase check and the hold's start are one step under the lock: aborts
        arrive from several threads at once (every viewer, the gamepad, the safety
        rules), and a repeated one must not restart the hold (phases.py). The
        sticks are centred either way; a refused abort (PhaseError) changes nothing.
        """
        now = self.clock.now()
        with self._lock:
            target = next_phase(self._phase, Action.ABORT)
            started = target is not self._phase
            if started:
                self._phase, self._abort_at = target, now
        self.operator.release(now=now, source="abort")
        if started:
            self._announce(target)

    def _run_action(self, action: Action, target: Phase) -> None:
        try:
            if action is Action.ARM:
                self.prearm.check(lambda: self.fleet_table.read(self.clock.now()),
                                  scale=self.operator.snapshot(self.clock.now()).demand.scale)
                self._for_all("arm", lambda p: p.arm())
                self._set_phase(target)
            elif action is Action.DISARM:
                self._for_all("disarm", lambda p: p.disarm())
                self._set_phase(target)
            elif action is Action.TAKEOFF:
                self._takeoff()
            elif action is Action.LAND:
                self._set_phase(target)
                self._for_all("land", lambda p: p.land())
            elif action is Action.RESUME:
                self._resume()
        except Exception as exc:  # report, never kill the worker
            self._event("error", f"{action.text} failed: {exc}")
            if action is Action.ARM and not isinstance(exc, PrearmError):  # none armed
                self._for_all("disarm", lambda p: p.disarm(), quiet=True)
                self._set_phase(Phase.READY)
        finally:
            self._action_busy.release()

    def _for_all(self, what: str, fn: Callable[[AutopilotProfile], None], *,
                 quiet: bool = False, only: Sequence[int] | None = None) -> None:
        """Run ``fn`` on every vehicle (or those with ids ``only``) in parallel; raise one
        error naming every failure."""
        ids = self.ids if only is None else tuple(only)
        outcomes = self.gate.map(self._pool, fn, [self.profiles[vid] for vid in ids])
        failures = [f"vehicle {vid}: {exc}" for vid, exc in zip(ids, outcomes, strict=True)
                    if exc is not None]
        if failures and not quiet:
            raise RuntimeError(f"{what}: " + "; ".join(failures))

    def _resume(self) -> None:
        """Switch back to the streaming mode the vehicles that left it while still flying.

        A vehicle coming down on its own (landing, disarmed) is not resumed: that
        one lands the team (gcs.loop._safety).
        """
        fleet = self.fleet_table.read(self.clock.now())
        out = [vid for vid, mode, want, down in zip(
            self.ids, fleet.modes, self._streaming_modes, self._coming_down(fleet), strict=True)
            if mode != want and not down]
        if not out:
            self._event("info", "resume: every flying vehicle is in its streaming mode already")
            return
        z = -self.operator.snapshot(self.clock.now()).altitude
        self._for_all("resume", lambda p: p.start_offboard(z_ned=z), only=out)
        for vid in out:
            self._event("info", f"resume: vehicle {vid} back in "
                                f"{self.profiles[vid].streaming_mode}")

    def _coming_down(self, fleet: FleetState) -> np.ndarray:
        """(n,) True where a vehicle is disarmed, in one of its profile's landing modes, or
        out of its streaming mode and more than :data:`COMING_DOWN_DROP_M` below the
        team's median altitude. The last: a mode whose descent is the pilot's (ArduCopter
        SITL switched to LOITER by MAVProxy, with no transmitter's throttle, fell to the
        ground), which the team holding above it learnt of only when it disarmed 12 s
        later."""
        down = ~fleet.armed | np.array([m in landing for m, landing in zip(
            fleet.modes, self._landing_modes, strict=True)], dtype=bool)
        alt = -fleet.p_ned[:, 2]
        if np.count_nonzero(np.isfinite(alt)) >= 2:
            out = np.array([m != want for m, want in zip(
                fleet.modes, self._streaming_modes, strict=True)], dtype=bool)
            down |= out & (alt < float(np.nanmedian(alt)) - COMING_DOWN_DROP_M)
        return down

    def _takeoff(self) -> None:
        cfg = self.team.config.flight
        self._set_phase(Phase.TAKING_OFF)
        scale = self.operator.snapshot(self.clock.now()).demand.scale
        h0 = self.taut_altitude(scale) - cfg.takeoff_slack
        self._for_all("take off", lambda p: p.takeoff(altitude_m=h0))
        deadline = time.monotonic() + cfg.takeoff_timeout
        reached = AltitudeReached()
        while True:
            fleet = self.fleet_table.read(self.clock.now())
            if reached.update(-fleet.p_ned[:, 2], h0, cfg.altitude_tolerance):
                break
            if self.phase is not Phase.TAKING_OFF:
                return  # aborted meanwhile
            if time.monotonic() > deadline:
                low = [vid for vid, m in zip(self.ids, reached.missing(), strict=True) if m]
                raise RuntimeError(f"vehicles {low} did not reach {h0:.2f} m in "
                                   f"{cfg.takeoff_timeout:g} s")
            for profile in self._profile_list:
                profile.keep_climbing()
            if not self.gate.pause():
                time.sleep(0.02)
        self.operator.reset_altitude(h0, now=self.clock.now())
        # The loop streams from here on: a vehicle confirmed in offboard must not wait
        # for the slowest one's confirmation without setpoints (its 0.5 s timeout
        # sent it to hold on a loaded machine).
        self._handing_over = True
        try:
            self._for_all("offboard", lambda p: p.start_offboard(z_ned=-h0))
        finally:
            self._handing_over = False
        if self.phase is Phase.TAKING_OFF:
            self._set_phase(Phase.HOVER)

    # -- the loop ------------------------------------------------------------------------

    def tick(self) -> RuntimeSnapshot:
        """One guidance tick; never raises for a vehicle's fault."""
        started, started_cpu = time.perf_counter(), time.thread_time()
        now = self.clock.now()
        # The phase before the fleet: a phase entered once every vehicle confirmed its mode
        # then never meets telemetry older than that confirmation.
        phase = self.phase
        fleet = self.fleet_table.read(now)
        if phase is Phase.CONNECT:  # presence is the pre-flight check's business
            verdict = SafetyVerdict(freeze=True, land=False, events=())
        else:
            # The mode rule, only where it applies and some vehicle is out of its mode
            # (one tuple comparison per tick otherwise).
            modes: tuple[str, ...] = ()
            coming_down = None
            if phase in _ON_GCS_SETPOINTS and fleet.modes != self._streaming_modes:
                modes = fleet.modes
                coming_down = self._coming_down(fleet)
            verdict = evaluate(self.team.config.safety, self.ids, fleet.age, fleet.p_ned,
                               safe_radius=self.safe_radius_for(self._accel_last), modes=modes,
                               expected=self._streaming_modes if modes else (),
                               coming_down=coming_down)
            self._recover(now, fleet, verdict, modes, coming_down)
            self._shape = self._watch_deformation(now, fleet, verdict, phase)
        self._report_safety(verdict)
        op = self.operator.snapshot(now)
        phase = self.phase  # an action may have moved it meanwhile
        self._report_modes(fleet, phase)
        if phase is Phase.CONNECT:
            self._preflight(fleet)
        elif phase is Phase.LANDING and np.all(np.isfinite(fleet.heartbeat_age)) \
                and not fleet.armed.any():
            self._set_phase(Phase.LANDED)
        if verdict.land and phase.airborne and phase not in (Phase.ABORTING, Phase.LANDING):
            self.request(Action.ABORT)
            phase = self.phase
        moving = phase is Phase.FORMATION and not verdict.freeze and op.guidance_on
        demand = op.demand if moving else MotionDemand(scale=op.demand.scale)
        self._streamed = None
        fence = None
        self._share_load(now, fleet, phase, op.demand.scale)
        if self._streams(phase):
            if self.follow_link_delay:
                self._follow_link_delay()
            if not verdict.freeze and fleet.located:
                fence = self._fence(fleet, demand)
                demand = fence.demand
            accel, self._accel_last = self._stream(
                fleet, demand, op, hold=self._shape in (Deformation.HOLD, Deformation.LAND),
                carrying=phase is Phase.FORMATION)
            self._streamed, self._streamed_at = accel, now
            self._advance(phase, op, now, fleet)
        else:
            accel, self._accel_last = np.zeros((fleet.n, 2)), 0.0
            # the next stream starts afresh (no gap to measure)
            self._last_send = self._last_send_clock = -math.inf
        errors = self.team.formation.distance_errors(fleet.p_ned[:, :2], demand.scale)
        truth = self.truth_source() if self.truth_source is not None else None
        phase = self.phase  # after this tick's transitions: the recorder and the snapshot agree
        if self.recorder is not None:
            arrays = {"dist_err": errors, "acc_cmd": accel, "tilt": fleet.tilt}  # NaN: unknown
            if self.load_sharing is not None:
                arrays["alt_trim"] = self.load_sharing.trims
            if truth is not None:
                arrays |= {"payload": np.array(truth.payload_p_ned + truth.payload_v_ned),
                           "rope_T": np.array(truth.rope_tension),
                           "veh_true": np.array(truth.vehicle_p_ned)}
            self.recorder.internals(now, arrays=arrays,
                                    sticks=(demand.forward, demand.right, demand.rotate),
                                    scale=demand.scale, altitude=op.altitude, phase=int(phase))
        self._compute.append(time.perf_counter() - started)
        cpu = time.thread_time() - started_cpu
        self._ticks += 1
        snap = RuntimeSnapshot(fleet=fleet, phase=phase, operator=op, demand=demand,
                               accel_cmd=accel, distance_errors=errors, safety=verdict,
                               compute_time=self._compute[-1], compute_cpu=cpu,
                               events=self.events()[-20:],
                               truth=truth, moving=moving, fence=fence,
                               recovery=self.recovery.status(now), shape=self._shape,
                               prearm=self.prearm.watch(now, fleet, scale=op.demand.scale)
                               if phase is Phase.READY else ())
        self._snapshot = snap
        # Lockstep: the phase actions and a scenario act now, while the sim stands still
        # at this tick's time; their effects show in the next tick.
        if not self.gate.window():
            self._warn_once(("gate", 0), "lockstep: a phase action was still busy "
                                         f"{HOLD_CAP_S:g} s after the tick; the sim went on")
        else:
            self._unlatch(("gate", 0))
        for listener in self._listeners:
            try:
                listener(snap)
            except Exception as exc:
                self._event("error", f"listener failed: {exc}")
        return snap

    def _preflight(self, fleet: FleetState) -> None:
        fresh = np.isfinite(fleet.age) & (fleet.age < self.team.config.safety.stale_after)
        if fresh.all() and np.all(np.isfinite(fleet.heartbeat_age)):
            if not self.analysis.ok and not self.analysis_override:
                self._warn_once(("analysis", 0), "pre-flight: gcs analyze fails: " +
                                self.analysis.violations[0].message)
                return
            self._set_phase(Phase.READY)

    def _stream(self, fleet: FleetState, demand: MotionDemand, op: OperatorSnapshot, *,
                hold: bool = False, carrying: bool = False) -> tuple[np.ndarray, float]:
        """Guidance and one setpoint per vehicle (errors are per vehicle): the accelerations
        sent and the largest one's norm. ``hold``: each vehicle holds where it was;
        ``carrying``: the payload hangs from the ropes (the spin's rope lead applies)."""
        if hold:
            accel = self._damping(fleet, self.deformation.hold_points)
            largest = finite_max_norm(accel)
        elif fleet.located:
            accel = self.guidance.accelerations(fleet.p_ned[:, :2], fleet.v_ned[:, :2],
                                                fleet.yaw, demand)
            accel = self._rope_lead(fleet, demand, accel, carrying=carrying)
            largest = finite_max_norm(accel)  # what the guidance could not compute becomes 0
        else:  # cannot place every vehicle: hold still horizontally
            accel, largest = np.zeros((fleet.n, 2)), 0.0
        self._send_all(accel, z_ned=-self._altitude(op))
        return accel, largest

    def _share_load(self, now: float, fleet: FleetState, phase: Phase, scale: float) -> None:
        """Move the load-sharing trims on this tick's thrusts, while every vehicle's thrust
        is fresh: each one's slack-rope thrust learnt below the band's lower half, the trims
        moved from its bottom up (where the ropes start to take the payload), the rate the
        ropes take it at followed while lifting; back to zero on the ground."""
        sharing = self.load_sharing
        if sharing is None:
            return
        if not phase.airborne:
            sharing.reset()
            self._shared_at = -math.inf
            return
        dt, self._shared_at = min(now - self._shared_at, _SHARE_DT_MAX), now
        if fleet.thrust is None or fleet.thrust_age is None:
            sharing.observe_carried(now, None, fleet.tilt)
            return
        cfg = self.team.config
        fresh = bool(np.all(fleet.thrust_age <= cfg.safety.stale_after)
                     and np.all(np.isfinite(fleet.thrust)) and np.all(np.isfinite(fleet.tilt)))
        if fresh:  # heard again, in any phase: a later silence is said again
            self._unlatch(("load sharing", 0))
        # the rate the ropes take the payload at, for the pickup's rope lead (not the
        # set-down's: the payload touching down is a step the lead came late for, and
        # pulled the square 0.07 m further in)
        sharing.observe_carried(now, fleet.thrust if fresh and phase is Phase.LIFTING
                                else None, fleet.tilt)
        altitude = float(np.mean(-fleet.p_ned[:, 2]))
        taut, below = self.taut_altitude(scale), cfg.flight.pickup_band[0]
        # every rope slack up to half the band below the taut-rope altitude: a take-off
        # that overshot into the band's lower half still leaves time to learn the slack
        if altitude < taut - below / 2 and fresh and phase in _SLACK_HOVER:
            sharing.observe_slack(dt, fleet.thrust, fleet.tilt)
        if altitude < taut - below:
            return
        if phase not in _CARRYING:
            return
        if fresh:
            sharing.update(dt, fleet.thrust, fleet.tilt)
            return
        silent = [vid for vid, age in zip(self.ids, fleet.thrust_age, strict=True)
                  if not age <= cfg.safety.stale_after]
        if silent:
            self._warn_once(("load sharing", 0), "load sharing held: no collective thrust "
                            "(ATTITUDE_TARGET) from vehicle(s) "
                            f"{', '.join(map(str, silent))}")

    def _rope_lead(self, fleet: FleetState, demand: MotionDemand, accel: np.ndarray, *,
                   carrying: bool) -> np.ndarray:
        """``accel`` plus the leads of the ropes' pulls (gcs/guidance/_rope_lead.py):
        turning with a spinning team (``carrying``: the payload hangs), and growing or
        shrinking as the ropes take or give up the payload (load sharing's rate);
        saturated again; unchanged when neither."""
        lag = self.team.config.guidance.rope_lag
        omega = self.guidance.angular_rate(demand) if carrying else 0.0
        if omega != 0.0 and lag > 0.0 and not self._ropes_pull(fleet):
            omega = 0.0
        sharing = self.load_sharing
        rate = sharing.carried_rate if sharing is not None else 0.0
        if lag <= 0.0 or (omega == 0.0 and rate == 0.0):
            return accel
        scale = demand.scale
        if self._rope_pull is None or self._rope_pull[0] != scale:
            try:
                pull = desired_load(self.team, scale=scale).force_ned[:, :2]
            except NoHangingPointError:  # ropes too short to hang it: nothing to lead
                pull = np.zeros((fleet.n, 2))
            self._rope_pull = (scale, np.ascontiguousarray(pull))
        heading = fit_rotation(scale * self.team.formation.positions, fleet.p_ned[:, :2])
        if heading is None:
            return accel
        pull_ned = rope_pull_ned(self._rope_pull[1], heading)
        mass = self.team.config.airframe.mass
        lead = rope_growth_lead(pull_ned, rate, lag, mass)
        if omega != 0.0:
            lead += rope_turn_lead(pull_ned, omega, lag, mass)
        lim = self.team.config.limits
        return saturate(accel + lead, norm_max=lim.accel_norm, axis_max=lim.accel_axis)

    def _ropes_pull(self, fleet: FleetState) -> bool:
        """Whether the ropes carry the payload, as the spin's rope lead assumes: not when
        every vehicle's fresh thrust says they carry under :data:`ROPE_LEAD_CARRIED_MIN` of
        its weight. A payload left on the ground, or copters with none (SITL): the lead,
        sized for the design's pulls and with no pull to cancel, spun four ArduCopter SITL
        copters up to 1.4 rad/s against the commanded 0.4 until the team tore apart.
        Unknown (no thrusts, or not fresh): assumed, as before there were thrusts."""
        sharing = self.load_sharing
        if sharing is None or fleet.thrust is None or fleet.thrust_age is None:
            return True
        if not np.all(fleet.thrust_age <= self.team.config.safety.stale_after):
            return True
        carried = sharing.carried(fleet.thrust, fleet.tilt)
        if not carried < ROPE_LEAD_CARRIED_MIN:  # NaN: not known
            return True
        self._warn_once(("rope lead", 0), f"the ropes carry {max(carried, 0.0):.2f} of the "
                        "payload's weight (from the vehicles' thrusts): the spin's rope lead "
                        "(guidance.rope_lag) is off")
        return False

    def _follow_link_delay(self) -> None:
        """The guidance predicts the distance errors half a period ahead, the hold's delay;
        over a radio the positions are a downlink old and the setpoints act an uplink
        late, so the prediction goes one round trip further (median of the last ten
        seconds of the slowest link's TIMESYNC). At 4 Hz with the paper's gains a 0.1 s
        link each way made the shape's stiffest mode oscillate (about 0.3 m, 6 s period,
        in the simulator behind a 100 ms relay); predicted further, it settles."""
        rtts = [r for r in (p.link.rtt_s for p in self._profile_list) if r is not None]
        if rtts:
            self._rtts.append(max(rtts))
        if self._rtts:
            delay = min(float(np.median(self._rtts)), LINK_DELAY_CAP_S)
            self.guidance.lead = self._base_lead + delay

    def _altitude(self, op: OperatorSnapshot) -> float:
        """The altitude setpoint: the operator's, never above the geofence's ceiling."""
        return min(op.altitude, self.team.config.safety.geofence_altitude)

    def _damping(self, fleet: FleetState, hold_points: np.ndarray | None = None) -> np.ndarray:
        """Velocity damping, saturated (NaN: zero), and with ``hold_points`` (n, 2) a pull of
        each vehicle back to its own point: the hold that cannot amplify a deformation
        whatever the positions say, since no vehicle's command depends on another's
        position (a frame that disagrees with the others' changes nothing).

        Damping alone let the shape drift with the wind (0.33 m in 10 s at hover in the
        simulator); the pull is critically damped (``HOLD_KP``, ``HOLD_KV``).
        """
        v = np.nan_to_num(fleet.v_ned[:, :2], nan=0.0, posinf=0.0, neginf=0.0)
        if hold_points is None:
            accel = -self.guidance.c1 * v
        else:
            offset = np.nan_to_num(fleet.p_ned[:, :2] - hold_points, nan=0.0)
            accel = -HOLD_KV * v - HOLD_KP * offset
        lim = self.team.config.limits
        return saturate(accel, norm_max=lim.accel_norm, axis_max=lim.accel_axis)

    def _fence(self, fleet: FleetState, demand: MotionDemand) -> FenceVerdict:
        """The demand limited by the geofence (the payload counts where it is known)."""
        p = fleet.p_ned[:, :2]
        f = self.team.formation
        heading = fit_rotation(demand.scale * f.positions, p)
        truth = self.truth_source() if self.truth_source is not None else None
        points = p if truth is None else np.vstack([p, np.array(truth.payload_p_ned[:2])])
        fence = fence_demand(self.team.config.safety, demand, heading=heading, points=points,
                             velocity=fleet.v_ned[:, :2].mean(axis=0), altitude=-fleet.p_ned[:, 2],
                             max_speed=self.guidance.max_speed, c1=self.guidance.c1)
        text = fence.text + (" (above the ceiling)" if fence.above else "")
        if text and text != self._fence_text:
            self._event("warning", text)
        self._fence_text = text
        return fence

    def _recover(self, now: float, fleet: FleetState, verdict: SafetyVerdict,
                 modes: tuple[str, ...], coming_down: np.ndarray | None) -> None:
        """Re-engage the vehicles that dropped out of the streaming mode, once the team is
        healthy again (:mod:`gcs.loop._recovery`)."""
        out: tuple[int, ...] = ()
        if modes and coming_down is not None:
            out = tuple(vid for vid, mode, want, down in zip(
                self.ids, modes, self._streaming_modes, coming_down, strict=True)
                if mode != want and not down)
        fresh = bool(np.all(fleet.age <= self.team.config.safety.stale_after))
        streaming = math.isfinite(self._last_send_clock)
        if not fresh or self._gap_seen or (streaming and now - self._last_send_clock > _GAP_S):
            self._gap_seen = False
            self.recovery.note_gap(now)
        healthy = fresh and fleet.located and not verdict.hold and not verdict.land
        if not self.recovery.update(now, out=out, healthy=healthy):
            return
        if not self._action_busy.acquire(blocking=False):
            return  # an action is running (a resume among them): the next try comes later
        self._event("info", f"recovery: every link fresh for "
                            f"{self.recovery.settle:g} s: re-engaging vehicles "
                            f"{', '.join(map(str, self.recovery.after_gap))}")
        self.gate.submit(self._pool, self._run_action, Action.RESUME, self.phase)

    def _on_record(self, record: TelemetryRecord) -> None:
        """A vehicle's failsafe message about lost setpoints is a gap (a link's thread): it
        left its mode because of the stream, not because someone switched it."""
        if isinstance(record, StatusText) and record.setpoints_lost:
            self.recovery.note_gap(self.clock.now())

    def _watch_deformation(self, now: float, fleet: FleetState, verdict: SafetyVerdict,
                           phase: Phase) -> Deformation:
        """Hold, re-form or land a team deformed beyond the safe bound
        (:mod:`gcs.loop._deformation`)."""
        policy = self.deformation
        p = fleet.p_ned[:, :2]
        fresh = bool(np.all(fleet.age <= self.team.config.safety.stale_after))
        if policy.observe(p, fleet.v_ned[:, :2], fleet.t - fleet.age,
                          in_shape=fresh and fleet.located and not verdict.hold):
            self._warn_once(("jump", 0), "a vehicle's position jumped: a deformation from "
                                         "here on is held, not re-formed")
        else:
            self._unlatch(("jump", 0))
        before = self._shape
        shape = policy.update(now, deformed=verdict.hold, deformation=verdict.deformation, p_xy=p)
        if shape is Deformation.LAND and phase.airborne \
                and phase not in (Phase.ABORTING, Phase.LANDING):
            self._event("error", f"deformation grew from {policy.held_at:.2f} to "
                                 f"{verdict.deformation:.2f} m: landing the team")
            self.request(Action.ABORT)
        elif shape is Deformation.REFORM and before is not Deformation.REFORM:
            self._event("warning", "re-forming the shape (motion frozen): the team was in "
                                   "shape and no position jumped, so the positions are trusted")
        return shape

    def _send_all(self, accel: np.ndarray, *, z_ned: float) -> None:
        """One setpoint per vehicle, packed for the whole fleet at once; an error is reported
        once per vehicle, never raised, and that vehicle's setpoint is not sent.

        ``accel`` is finite (:meth:`_stream` zeroes what the guidance could not compute).
        """
        if not math.isfinite(z_ned):  # never reaches a vehicle, whatever its profile
            for i in range(len(self.ids)):
                self._not_sent(i, f"altitude target not finite: {z_ned}")
            return
        vertical = np.full(len(self.ids), z_ned)
        if self.load_sharing is not None:  # trimmed, never above the geofence's ceiling
            vertical = np.maximum(vertical + self.load_sharing.trims,
                                  min(z_ned, -self.team.config.safety.geofence_altitude))
        only = None
        if self._vertical_calls:  # profiles whose vertical channel is not z itself
            only = self._vertical_from_profiles(vertical)
        with self._send_lock:
            wall, now = time.monotonic(), self.clock.now()
            # on the loop's clock, which the vehicles' timeouts run on (the simulator's in
            # simulation: a stopped simulator is no gap, a stopped GCS is)
            gap = now - self._last_send_clock  # inf: the first round of a stream
            if math.isfinite(gap):
                self._gap_max = max(self._gap_max, gap)
                if gap > _GAP_S:
                    self._gap_seen = True
            self._last_send, self._last_send_clock = wall, now
            packed = self._packer.pack(wall, accel, vertical)
            failed = self._fanout.send(packed, SETPOINT_MESSAGE.crc_extra, only)
        for i, exc in failed.items():
            self._not_sent(i, exc)

    def _vertical_from_profiles(self, vertical: np.ndarray) -> list[int] | None:
        """Fill in the vertical channel of the profiles that compute it from each vehicle's
        altitude target in ``vertical``; the rows that can be sent (None: all), having
        reported why each other one cannot."""
        refused = []
        for i, vertical_setpoint in self._vertical_calls:
            try:
                value = float(vertical_setpoint(float(vertical[i])))
            except Exception as exc:
                refused.append(i)
                self._not_sent(i, exc)
                continue
            if not math.isfinite(value):
                refused.append(i)
                self._not_sent(i, f"vertical setpoint not finite: {value}")
                continue
            vertical[i] = value
        if not refused:
            return None
        vertical[refused] = 0.0  # packed, never sent
        return sorted(set(range(len(vertical))) - set(refused))

    def _not_sent(self, i: int, why: Exception | str) -> None:
        """Warn once that vehicle ``i``'s setpoint was not sent, and why."""
        vid = self.ids[i]
        reason = why.what if isinstance(why, LinkError) else str(why)
        self._warn_once(("send", vid), f"vehicle {vid}: setpoint not sent: {reason}")

    def _streams(self, phase: Phase) -> bool:
        """Whether the loop sends setpoints in ``phase`` (and during the offboard handover)."""
        return phase.streaming or (phase is Phase.TAKING_OFF and self._handing_over)

    def resend(self) -> bool:
        """Re-send the last tick's setpoints (the altitude target's ramp moves on); False if
        the last tick streamed none or the phase stopped streaming since.

        More than :data:`HELD_SETPOINT_S` after its tick, the loop is stalled: the
        re-send damps velocity only (:meth:`_damping`) on the latest telemetry.
        """
        accel = self._streamed
        if accel is None or not self._streams(self.phase):
            return False
        now = self.clock.now()
        if now - self._streamed_at > HELD_SETPOINT_S:
            accel = self._damping(self.fleet_table.read(now))
        self._send_all(accel, z_ned=-self._altitude(self.operator.snapshot(now)))
        self.resends += 1
        return True

    def _advance(self, phase: Phase, op: OperatorSnapshot, now: float,
                 fleet: FleetState) -> None:
        # The ramp's end and the team's own altitude: a team held up (vehicles in hold
        # after a gap) has not lifted or set down its payload when the ramp ends.
        target = min(op.altitude_target, self.team.config.safety.geofence_altitude)
        if phase is not self._reached_in:
            self._reached_in = phase
            self._reached.reset()
        there = self._reached.update(-fleet.p_ned[:, 2], target,
                                     self.team.config.flight.altitude_tolerance)
        reached = abs(op.altitude - op.altitude_target) < 1e-6 and there
        if phase is Phase.LIFTING and reached:
            self._set_phase(Phase.FORMATION)
        elif phase is Phase.SETTING_DOWN and reached:
            self._set_phase(Phase.HOVER)
        elif (phase is Phase.ABORTING and self._abort_at is not None
              and now - self._abort_at >= self.team.config.flight.abort_hold):
            self._abort_at = None
            self._set_phase(Phase.LANDING)
            if self._action_busy.acquire(blocking=False):
                self.gate.submit(self._pool, self._run_action, Action.LAND, Phase.LANDING)
            else:  # an action is stuck: land directly
                self.gate.submit(self._pool, functools.partial(
                    self._for_all, "land", lambda p: p.land(), quiet=True))

    def _report_modes(self, fleet: FleetState, phase: Phase) -> None:
        """A vehicle changing mode on its own while the GCS streams is a warning."""
        if fleet.modes == self._modes_seen:  # one comparison on most ticks, not one per vehicle
            return
        self._modes_seen = fleet.modes
        for vid, mode, streaming in zip(fleet.ids, fleet.modes, self._streaming_modes,
                                        strict=True):
            before = self._modes.get(vid)
            self._modes[vid] = mode
            if before is not None and mode != before:
                # from lifting on, every vehicle must stay in the mode the GCS put it in
                # (its streaming mode, whose HEARTBEAT may come after the lift began)
                level = "warning" if phase in (Phase.LIFTING, Phase.FORMATION,
                                               Phase.SETTING_DOWN) and mode != streaming \
                    else "info"
                self._event(level, f"vehicle {vid}: mode {mode} (was {before})")

    def _report_safety(self, verdict: SafetyVerdict) -> None:
        active = set()
        for e in verdict.events:
            key = (e.reason.name, e.vehicle)
            active.add(key)
            if key not in self._active_warnings:
                self._event("warning", e.text)
        self._active_warnings = active

    def _warn_once(self, key: tuple[str, int], text: str) -> None:
        """Say ``text`` once for a condition that may hold tick after tick; again only
        after :meth:`_unlatch` (the condition cleared). Some are never unlatched: a
        setpoint that cannot be sent, the analysis, the rope lead turned off."""
        if key not in self._latched:
            self._latched.add(key)
            self._event("warning", text)

    def _unlatch(self, key: tuple[str, int]) -> None:
        """The condition behind ``key`` cleared: its next occurrence is said again."""
        self._latched.discard(key)

    def stats(self) -> TickStats:
        """Loop timing over the recent ticks."""
        comp = np.array(self._compute) if self._compute else np.zeros(1)
        jit = np.array(self._jitter) if self._jitter else np.zeros(1)
        return TickStats(ticks=self._ticks, compute_last=float(comp[-1]),
                         compute_p99=float(np.percentile(comp, 99)),
                         jitter_p99=float(np.percentile(jit, 99)), overruns=self._overruns,
                         stall_max=self._stall_max, setpoint_gap_max=self._gap_max)

    def run(self, stop: threading.Event) -> None:
        """Tick at the guidance rate on the clock until ``stop`` is set (or the clock dies).

        With more than one setpoint per tick, a thread of its own re-sends them
        (:meth:`_keep_streaming`). After a stall longer than a period the loop
        ticks at once and restarts its schedule from there (it skips, never
        bursts); the stall is an event, recorded, and counted in :meth:`stats`.
        """
        done = threading.Event()
        keeper = None
        if self.setpoints_per_tick > 1:
            keeper = threading.Thread(target=self._keep_streaming, args=(done, stop),
                                      daemon=True, name="gcs-setpoints")
            keeper.start()
        try:
            self._tick_forever(stop)
        finally:
            done.set()
            # No more ticks: release whoever waits for one (a scenario parked at the gate
            # when the sim clock stopped waited for ever), so that they see why.
            self.gate.close()
            if keeper is not None:
                keeper.join(timeout=1.0)

    def _tick_forever(self, stop: threading.Event) -> None:
        k = 0
        start = self.clock.now()
        while not stop.is_set():
            due = start + k * self.period
            try:
                self.clock.sleep_until(due)
            except ClockStoppedError as exc:
                self._event("error", f"loop stopped: {exc}")
                return
            now = self.clock.now()
            if k == 0:  # the schedule starts at the clock's first time (a simulator's first
                start = due = now  # sample, whether it came before the loop started or not)
            late = now - due
            self._stall_max = max(self._stall_max, late)
            if late > self.period:
                self.recovery.note_gap(now)
                self._overruns += 1
                self._event("warning", f"loop stalled: tick {late:.2f} s late")
                start, k = now, 0  # tick now, then keep the schedule from here
            try:
                self._jitter.append(late)
                self.tick()
            except Exception as exc:  # a bug must not stop the team's setpoint stream silently
                self._event("error", f"tick failed: {type(exc).__name__}: {exc}")
            k += 1

    def _keep_streaming(self, done: threading.Event, stop: threading.Event) -> None:
        """Re-send the latest setpoints whenever a slot (``period / setpoints_per_tick``) of
        wall time passed without a round, whatever the loop is doing."""
        slot = self.period / self.setpoints_per_tick
        while not (done.is_set() or stop.is_set()):
            wait = self._last_send + slot - time.monotonic()
            if wait > 0.0:
                done.wait(wait)
                continue
            try:
                sent = self.resend()
            except Exception as exc:  # report, and keep the stream alive
                self._warn_once(("resend", 0), f"setpoint re-send failed: "
                                               f"{type(exc).__name__}: {exc}")
                sent = False
            else:
                self._unlatch(("resend", 0))
            if not sent:
                done.wait(slot)

    def close(self) -> None:
        """Stop the worker threads (does not land: that is the operator's or abort's job)."""
        self.gate.close()
        self._pool.shutdown(wait=False, cancel_futures=True)


def _load_sharing(team: Team) -> LoadSharing | None:
    """The team's load sharing (:mod:`gcs.loop._load_share`), toward the split at the
    desired shape; None when off, or when the team has no free split or no hanging point."""
    fl = team.config.flight
    if not fl.load_sharing:
        return None
    try:
        target = desired_load(team).share
    except NoHangingPointError:
        return None
    sharing = LoadSharing(team.formation.positions, target,
                          vehicle_mass=team.config.airframe.mass,
                          payload_mass=team.config.payload.mass, gain=fl.load_share_gain,
                          trim_max=fl.load_share_trim_max)
    return sharing if sharing.active else None
