"""The GCS loop: operator sticks in, one acceleration setpoint per vehicle out, at 4 Hz.

Each tick (scheduled on a :class:`~gcs.loop.Clock`, wall or simulator time) runs
the stages in this order; gcs/loop/README.md maps what each reads and writes:

1. fleet: the team's latest telemetry (:class:`~gcs.loop.FleetTable`);
2. safety: the tick's verdict, recovery and deformation (``_safety_stage``);
3. phase: ready, landed, or the abort a rule asks for (``_phase_stage``);
4. demand: the operator's command, frozen or fenced (``_demand_stage``);
5. load sharing: the altitude trims (``_load_share_stage``);
6. guidance: one acceleration per vehicle (``_guidance_stage``);
7. setpoints: to the link layer's stream (``_setpoint_stage``);
8. phase: lifted, set down, abort's hold over (``_phase_stage``);
9. record: the internals, the snapshot, the listeners (``_record``, ``_snapshot``).

Phase actions that wait for acknowledgements (arm, take off, land) run on a
worker thread (``_actions``), so the loop never waits on a vehicle. Nothing
about one vehicle stops the loop: it is reported (``_events``) and the loop goes on.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from gcs.analysis import Analysis, analyze
from gcs.config import Team
from gcs.guidance import Guidance, finite_max_norm
from gcs.link import AutopilotProfile, SetpointStream
from gcs.loop._actions import ActionRunner
from gcs.loop._clock import Clock, ClockStoppedError
from gcs.loop._deformation import Deformation
from gcs.loop._demand_stage import DemandStage
from gcs.loop._events import Event, EventLog
from gcs.loop._fleet import FleetTable
from gcs.loop._guidance_stage import GuidanceStage
from gcs.loop._load_share_stage import LoadShareStage
from gcs.loop._operator import OperatorCommand
from gcs.loop._phase_machine import PhaseMachine
from gcs.loop._phase_stage import PhaseStage
from gcs.loop._phases import Action, Phase
from gcs.loop._prearm import Prearm
from gcs.loop._record import FlightRecorder, record_team, record_tick
from gcs.loop._rope_lead_stage import RopeLead
from gcs.loop._safety import evaluate
from gcs.loop._safety_stage import GAP_S, SafetyStage
from gcs.loop._setpoint_stage import SetpointStage
from gcs.loop._snapshot import RuntimeSnapshot, TickStats, TickTimer
from gcs.loop._stepgate import HOLD_CAP_S, StepGate
from gcs.loop._team_frame import TeamFrame
from gcs.loop._vehicle_modes import VehicleModes
from gcs.wire import SimTruth

__all__ = ["Runtime", "Stages"]


@dataclass(frozen=True)
class Stages:
    """The tick's stages, in the order the tick runs them (gcs/loop/README.md)."""

    safety: SafetyStage
    phase: PhaseStage
    demand: DemandStage
    load_share: LoadShareStage
    guidance: GuidanceStage
    setpoints: SetpointStage


class Runtime:
    """The formation loop of one team: its stages, wired, and the schedule they tick on.

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
        gate: lets phase actions act only at ticks in lockstep (default: disabled).
    """

    def __init__(self, team: Team, profiles: Mapping[int, AutopilotProfile], clock: Clock,
                 operator: OperatorCommand, *, recorder: FlightRecorder | None = None,
                 analysis: Analysis | None = None,
                 truth_source: Callable[[], SimTruth | None] | None = None,
                 setpoints_per_tick: int | None = None, gate: StepGate | None = None) -> None:
        self.team, self.ids = team, team.formation.ids
        missing = [vid for vid in self.ids if vid not in profiles]
        if missing:
            raise ValueError(f"no link configured for vehicle(s) {missing}")
        per_tick = (team.config.guidance.setpoints_per_tick
                    if setpoints_per_tick is None else setpoints_per_tick)
        if per_tick < 1:
            raise ValueError(f"setpoints_per_tick must be at least 1, got {setpoints_per_tick}")
        self.setpoints_per_tick = per_tick
        self.profiles, self.clock, self.operator = profiles, clock, operator
        self.recorder, self.truth_source = recorder, truth_source
        self.period = 1.0 / team.config.guidance.rate_hz
        self.analysis: Analysis = analysis if analysis is not None else analyze(team)
        self.gate = gate if gate is not None else StepGate(enabled=False)
        """Lets phase actions act only at ticks in lockstep (disabled otherwise)."""
        ordered = [profiles[vid] for vid in self.ids]
        self.fleet_table = FleetTable(self.ids, profiles)
        """The team's latest telemetry, kept current by the links (the UI reads it too)."""
        _warm_up(team, self.fleet_table)
        self.event_log = EventLog(clock.now, recorder)
        """What the operator is told: every stage's events and warnings."""
        self.phases = PhaseMachine(self.event_log)
        """The flight phase (:attr:`phase` reads it)."""
        if recorder is not None:  # before anything sends (the team frame may)
            record_team(recorder, team, profiles, clock)
        self.team_frame = TeamFrame(team, profiles, self.fleet_table, note=self.note)
        """Where each vehicle's local frame lies in the team frame the fleet table reads in."""
        self.prearm = Prearm(team, self.analysis, self.team_frame, profiles, note=self.note)
        """The checks an arm must pass."""
        self.modes = VehicleModes(ordered)
        """Each vehicle's streaming and landing modes, and the changes seen."""
        self.actions = ActionRunner(team, profiles, fleet_table=self.fleet_table, clock=clock,
                                    operator=operator, gate=self.gate, prearm=self.prearm,
                                    phases=self.phases, events=self.event_log,
                                    modes=self.modes)
        """The operator's phase actions, on worker threads."""
        self.stages = self._stages(ordered)
        """The tick's stages, in the order it runs them."""
        self._timer = TickTimer()
        self._snapshot: RuntimeSnapshot | None = None
        self._listeners: list[Callable[[RuntimeSnapshot], None]] = []
        self.recovery = self.stages.safety.recovery
        self.deformation = self.stages.safety.deformation
        self.load_sharing = self.stages.load_share.sharing
        """The load-sharing trims (None: off, or a team with no free split)."""

    def _stages(self, ordered: list[AutopilotProfile]) -> Stages:
        team, events = self.team, self.event_log
        stream = SetpointStream(
            ordered, clock=self.clock.now, gap_s=GAP_S, on_unsent=lambda vid, why:
            events.warn_once(("send", vid), f"vehicle {vid}: setpoint not sent: {why}"))
        guidance = Guidance.from_team(team)
        load_share = LoadShareStage(team, events)
        guidance_stage = GuidanceStage(team, guidance, RopeLead(team, guidance,
                                                                load_share.sharing, events))
        return Stages(
            safety=SafetyStage(team, self.analysis, self.profiles, clock=self.clock,
                               modes=self.modes, stream=stream, actions=self.actions,
                               phases=self.phases, events=events),
            phase=PhaseStage(team, self.analysis, phases=self.phases, actions=self.actions,
                             events=events),
            demand=DemandStage(team, guidance, ordered, truth_source=self.truth_source,
                               events=events,
                               follow_link_delay=not self.gate.enabled and guidance.lead > 0),
            load_share=load_share, guidance=guidance_stage,
            setpoints=SetpointStage(
                team, stream, clock=self.clock, operator=self.operator,
                fleet_table=self.fleet_table, guidance=guidance_stage, events=events,
                phase=lambda: self.phases.phase,
                handing_over=lambda: self.actions.handing_over,
                trims=lambda: load_share.trims))

    # -- what the page, the scenarios and the metrics read ------------------------------

    @property
    def phase(self) -> Phase:
        return self.phases.phase

    @property
    def snapshot(self) -> RuntimeSnapshot | None:
        """The latest tick's snapshot (None before the first tick)."""
        return self._snapshot

    def events(self) -> tuple[Event, ...]:
        """Recent events, oldest first."""
        return self.event_log.recent()

    @property
    def errors(self) -> int:
        """Error events so far (the event list keeps only the recent ones)."""
        return self.event_log.errors

    @property
    def resends(self) -> int:
        """Setpoint rounds re-sent between ticks so far."""
        return self.stages.setpoints.stream.resends

    @property
    def analysis_override(self) -> bool:
        """Fly although the analysis fails (``--override-analysis``): the user's call."""
        return self.stages.phase.analysis_override

    @analysis_override.setter
    def analysis_override(self, value: bool) -> None:
        self.stages.phase.analysis_override = value

    @property
    def action_running(self) -> bool:
        """Whether a phase action (arm, take off, land, resume...) is still running."""
        return self.actions.running

    def add_listener(self, callback: Callable[[RuntimeSnapshot], None]) -> None:
        """Call ``callback(snapshot)`` after every tick (on the loop thread: keep it short)."""
        self._listeners.append(callback)

    def note(self, level: str, text: str) -> None:
        """Add an event from outside the loop (link presence, UI, gamepad): shown and logged."""
        self.event_log.note(level, text)

    def request(self, action: Action) -> None:
        """Start a phase action; returns at once. PhaseError if the phase does not allow it."""
        self.actions.request(action)

    def stats(self) -> TickStats:
        """Loop timing over the recent ticks."""
        return self._timer.stats(setpoint_gap_max=self.stages.setpoints.stream.gap_max)

    # -- the tick ------------------------------------------------------------------------

    def tick(self) -> RuntimeSnapshot:
        """One guidance tick, its stages in order; never raises for a vehicle's fault."""
        started, started_cpu = time.perf_counter(), time.thread_time()
        now = self.clock.now()
        st = self.stages
        # The phase before the fleet: a phase entered once every vehicle confirmed its mode
        # then never meets telemetry older than that confirmation.
        phase = self.phases.phase
        fleet = self.fleet_table.read(now)
        verdict = st.safety.judge(now, phase, fleet, commanded=st.guidance.largest)
        op = self.operator.snapshot(now)
        phase = self.phases.phase  # an action may have moved it meanwhile
        self.modes.report(fleet, phase, self.event_log)
        phase = st.phase.settle(phase, fleet, verdict)
        moving, demand = st.demand.motion(phase, verdict, op)
        st.setpoints.hold_back()
        fence = None
        st.load_share.update(now, fleet, phase, op.demand.scale)
        if st.setpoints.streams(phase):
            demand, fence = st.demand.limit(fleet, demand, verdict)
            accel = st.guidance.accelerations(
                fleet, demand, hold=st.safety.shape in (Deformation.HOLD, Deformation.LAND),
                hold_points=self.deformation.hold_points, carrying=phase is Phase.FORMATION)
            st.setpoints.send(now, accel, op)
            st.phase.advance(phase, op, now, fleet)
        else:
            accel = st.guidance.idle(fleet.n)
            st.setpoints.stop()
        errors = self.team.formation.distance_errors(fleet.p_ned[:, :2], demand.scale)
        truth = self.truth_source() if self.truth_source is not None else None
        phase = self.phases.phase  # after this tick's transitions: record and snapshot agree
        if self.recorder is not None:
            record_tick(self.recorder, now, errors=errors, accel=accel, tilt=fleet.tilt,
                        trims=st.load_share.trims, truth=truth, demand=demand, op=op,
                        phase=phase)
        compute = time.perf_counter() - started
        self._timer.computed(compute)
        snap = RuntimeSnapshot(fleet=fleet, phase=phase, operator=op, demand=demand,
                               accel_cmd=accel, distance_errors=errors, safety=verdict,
                               compute_time=compute,
                               compute_cpu=time.thread_time() - started_cpu,
                               events=self.events()[-20:], truth=truth, moving=moving,
                               fence=fence, recovery=self.recovery.status(now),
                               shape=st.safety.shape,
                               prearm=self.prearm.watch(now, fleet, scale=op.demand.scale)
                               if phase is Phase.READY else ())
        self._publish(snap)
        return snap

    def _publish(self, snap: RuntimeSnapshot) -> None:
        """The tick's snapshot to its readers; in lockstep, the phase actions and a scenario
        act now, while the sim stands still at this tick's time (their effects show in the
        next tick)."""
        self._snapshot = snap
        if not self.gate.window():
            self.event_log.warn_once(("gate", 0), "lockstep: a phase action was still busy "
                                     f"{HOLD_CAP_S:g} s after the tick; the sim went on")
        else:
            self.event_log.unlatch(("gate", 0))
        for listener in self._listeners:
            try:
                listener(snap)
            except Exception as exc:
                self.event_log.add("error", f"listener failed: {exc}")

    # -- the schedule --------------------------------------------------------------------

    def run(self, stop: threading.Event) -> None:
        """Tick at the guidance rate on the clock until ``stop`` is set (or the clock dies).

        With more than one setpoint per tick, the link layer re-sends them between
        ticks on a thread of its own. After a stall longer than a period the loop
        ticks at once and restarts its schedule from there (it skips, never
        bursts); the stall is an event, recorded, and counted in :meth:`stats`.
        """
        end_resends = self.stages.setpoints.resend_until(stop, per_tick=self.setpoints_per_tick,
                                                   period=self.period)
        try:
            self._tick_forever(stop)
        finally:
            # No more ticks: release whoever waits for one (a scenario parked at the gate
            # when the sim clock stops would wait for ever), so that they see why.
            self.gate.close()
            end_resends()

    def _tick_forever(self, stop: threading.Event) -> None:
        k = 0
        start = self.clock.now()
        while not stop.is_set():
            due = start + k * self.period
            try:
                self.clock.sleep_until(due)
            except ClockStoppedError as exc:
                self.event_log.add("error", f"loop stopped: {exc}")
                return
            now = self.clock.now()
            if k == 0:  # the schedule starts at the clock's first time (a simulator's first
                start = due = now  # sample, whether it came before the loop started or not)
            late = now - due
            self._timer.started(late)
            if late > self.period:
                self.recovery.note_gap(now)
                self._timer.overruns += 1
                self.event_log.add("warning", f"loop stalled: tick {late:.2f} s late")
                start, k = now, 0  # tick now, then keep the schedule from here
            try:
                self.tick()
            except Exception as exc:  # a bug must not stop the team's setpoint stream silently
                self.event_log.add("error", f"tick failed: {type(exc).__name__}: {exc}")
            k += 1

    def close(self) -> None:
        """Stop the worker threads (does not land: that is the operator's or abort's job)."""
        self.gate.close()
        self.actions.close()


def _warm_up(team: Team, fleet_table: FleetTable) -> None:
    """Load the tick's compiled kernels now, on the arrays the tick passes them: compiling
    or loading them at the first tick would make it late."""
    fleet = fleet_table.read(0.0)
    _ = fleet.located
    evaluate(team.config.safety, team.formation.ids, fleet.age, fleet.p_ned, safe_radius=1.0)
    team.formation.distance_errors(fleet.p_ned[:, :2])
    finite_max_norm(np.zeros((fleet.n, 2)))
