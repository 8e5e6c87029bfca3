"""``gcs fly``: a headless flight of a scenario, simulated or on real autopilots, and its
metrics.

Starts the simulated team behind zenoh (or joins a running ``gcs sim``), plays
the scenario through the same operator command and phase actions as the
browser, and returns the flight metrics. With the sim started here the GCS and
the sim run in lockstep, so the flight is as fast as the machine allows (or
paced with ``speed``) and repeatable. A team whose ``links:`` reach PX4 or
ArduPilot autopilots flies as ``gcs run`` flies it instead: no simulator, on the
wall clock, without faults or ground truth. :class:`HeadlessFlight` is that
flight, played by a scenario here and call by call by :mod:`gcs.testing`.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from gcs.analysis import analyze
from gcs.app._app import GcsApp
from gcs.app._scenario import Scenario, ScenarioError, Step, play, play_step
from gcs.app._simprocess import SimProcess
from gcs.common import ConfigError
from gcs.config import Team, seal_key, signing_line
from gcs.flightlog import FlightMetrics
from gcs.loop import Action, GatedClock, Phase, RuntimeSnapshot
from gcs.transport import ZenohSettings
from gcs.wire import Sealer, SimTruth, keys

__all__ = ["CONTROL_ANSWER_S", "REAL_PROFILES", "FlightResult", "HeadlessFlight",
           "flies_real_vehicles", "fly"]

CONTROL_ANSWER_S = 10.0
"""Longest wall time the simulator may take to answer a control message, s."""

REAL_PROFILES = frozenset({"px4", "ardupilot"})
"""The link profiles of real autopilots (and of their SITL)."""

LAND_BEFORE_EXIT_S = 120.0
"""Longest a failed flight on real vehicles waits for the team it aborted to land, s."""


def flies_real_vehicles(team: Team) -> bool:
    """Whether ``team``'s ``links:`` reach real autopilots (a px4 or ardupilot profile).

    Such a team is flown as ``gcs run`` flies it: no simulator is started, the
    loop runs on the wall clock (a real vehicle cannot be paced or stepped), and
    what only a simulator has (faults on command, ground truth) is unavailable.
    """
    return any(link.profile in REAL_PROFILES for link in team.config.links or ())


def _check_real(team: Team, speed: str | None, connect: str | None) -> None:
    """Refuse what a flight of real vehicles cannot do, naming why (one line)."""
    if connect is not None:
        raise ConfigError("--connect", "", f"joins a running simulator, but the links of "
                          f"{team.source} reach px4/ardupilot autopilots: leave it out")
    if speed is not None:
        try:
            one = float(speed) == 1.0
        except ValueError:
            one = False
        if not one:
            raise ConfigError("--speed", "", f"the links of {team.source} reach px4/ardupilot "
                              f"autopilots, which fly on the wall clock: speed 1 only, "
                              f"got {speed!r}")


@dataclass
class FlightResult:
    """Metrics of a flight and, if it did not complete, why."""

    metrics: dict[str, object]
    error: str | None
    record: str | None

    def to_json(self) -> dict[str, object]:
        return {**self.metrics, "completed": self.error is None, "error": self.error,
                "record": self.record}


class HeadlessFlight:
    """A team flying headless on the simulator's clock, played by the thread that starts it.

    Starts the simulator (or joins ``connect``) and a :class:`GcsApp` following its
    clock, in lockstep with a simulator started here (``lockstep``): the thread
    that calls :meth:`start` is then a participant of the lockstep, so the steps
    it plays and the faults it injects act at ticks, and a flight is the same on
    every run. Every tick feeds the flight's metrics.

    A team on px4/ardupilot links (:func:`flies_real_vehicles`, :attr:`real`) starts
    no simulator: the GCS reaches the vehicles through the team file's links and
    runs on the wall clock (``speed`` 1 only; ``connect``, ``seed`` and ``lockstep``
    do not apply), faults are refused and the metrics leave out ground truth.

    Why a class: ``gcs fly`` plays a scenario file through it and
    :mod:`gcs.testing` (``SimTeam``, ``Team.connect``) one step per call, so a
    scripted flight has one implementation.

    Args:
        team: the loaded team.
        speed: the simulator's pace, sim seconds per wall second, or ``"max"``
            (default; real vehicles: 1, the only pace they take).
        record: .tlog file to record to, or None.
        connect: zenoh endpoint of a running simulator to join instead of starting one.
        seed: of the started simulator's sensor noise and gusts.
        gusts: the started simulator's turbulence, m/s per axis (``python -m sim
            --gusts``; None: its world's, calm).
        override_analysis: fly although ``gcs analyze`` refuses the team.
        lockstep: acknowledge every tick of the simulator started here, or of the one
            joined if it was started with ``--lockstep`` (refused at once where that
            cannot be sound: :mod:`gcs.app._simjoin`).
        say: gets the line on how the team is signed (the key is made before the sim),
            and what a failed flight on real vehicles does before it ends.
        ready_timeout: longest wait for the simulator started here to come up, s.
        fork_server: fork the simulator from this process's warm server
            (:class:`SimProcess`): True where a process flies many (the API, the seeds of a
            Monte-Carlo run); ``gcs fly``'s one flight starts a fresh one.
    """

    def __init__(self, team: Team, *, speed: str | None = None, record: Path | None = None,
                 connect: str | None = None, seed: int = 0, override_analysis: bool = False,
                 lockstep: bool = True, say: Callable[[str], None] | None = None,
                 ready_timeout: float = 60.0, gusts: float | None = None,
                 fork_server: bool = True) -> None:
        self.team = team
        self._say = say if say is not None else (lambda _line: None)
        self.real = flies_real_vehicles(team)
        """The team's links reach real autopilots: wall clock, no simulator."""
        if self.real:
            _check_real(team, speed, connect)
        if not override_analysis:
            _refuse_unless_analysed(team)
        if gusts is not None and (self.real or connect is not None):
            where = (f"the links of {team.source} reach px4/ardupilot autopilots"
                     if self.real else f"the simulator joined at {connect} has its own "
                     f"(python -m sim --gusts)")
            raise ConfigError("--gusts", "", f"sets the wind of a simulator started here, but "
                              f"{where}: leave it out")
        line = signing_line(team.config.gcs, Path(team.source).parent)  # the key, before the sim
        if say is not None:
            say(line)
            if self.real:
                say(f"flying the vehicles {team.source}'s links reach, on the wall clock (no "
                    f"simulator): faults and ground truth are not available")
        self.sim: SimProcess | None = None
        self.endpoint: str | None = None
        """The simulator's zenoh endpoint (None: real vehicles)."""
        settings: ZenohSettings | None = None  # real vehicles: the team file's own
        if self.real:
            lockstep = False
        elif connect is None:
            self.sim = SimProcess.on_free_port(
                team, speed=speed or "max", lockstep=lockstep, signing=team.config.gcs.signing,
                extra=("--seed", str(seed), *(() if gusts is None else ("--gusts", repr(gusts)))),
                ready_timeout=ready_timeout, fork_server=fork_server)
            self.endpoint = self.sim.endpoint
        else:
            if speed is not None:
                raise ConfigError("--speed", "", f"paces a simulator started here; the one "
                                  f"joined at {connect} runs at its own --speed "
                                  f"(python -m sim --speed): leave it out")
            self.endpoint = connect
        if self.endpoint is not None:
            # a simulator elsewhere is joined as the team file says (TLS across machines);
            # the one started here listens on loopback in the clear
            settings = ZenohSettings(mode="peer", connect=(self.endpoint,),
                                     tls=team.config.gcs.zenoh.tls if connect is not None
                                     else None)
        self.metrics = FlightMetrics()
        self._metrics_lock = threading.Lock()
        self._counted: RuntimeSnapshot | None = None  # the latest tick in the metrics
        self._wall0 = time.monotonic()
        self._wall_end: float | None = None
        self._playing = contextlib.ExitStack()
        self._player: int | None = None  # the thread that plays
        try:
            self.app = GcsApp(team, zenoh_settings=settings, sim_clock=not self.real,
                              # joined: in lockstep if the simulator is (its clock says)
                              lockstep=None if connect is not None and lockstep
                              else lockstep and self.sim is not None, record=record,
                              override_analysis=override_analysis)
        except BaseException:
            if self.sim is not None:
                self.sim.close()
            raise
        self.app.add_listener(self._on_tick)
        self.clock = GatedClock(self.app.clock, self.app.gate)
        """The clock steps wait on: in lockstep they park at ticks."""
        self._sealer: Sealer | None = None  # seals control messages (made at the first)
        self._closed = False

    def _on_tick(self, snap: RuntimeSnapshot, _truth: SimTruth | None) -> None:
        with self._metrics_lock:
            self.metrics.add(self._measured(snap))
            self._counted = snap

    def _measured(self, snap: RuntimeSnapshot) -> RuntimeSnapshot:
        """What the metrics take of a tick: on real vehicles no ground truth, even if a
        simulator on the team's zenoh publishes some (its payload is not theirs)."""
        return dataclasses.replace(snap, truth=None) if self.real else snap

    def start(self) -> None:
        """Start the loop, the calling thread a participant of the lockstep from now on."""
        self._player = threading.get_ident()
        self._playing.enter_context(self.app.gate.participant())
        self.app.start()

    def play(self, scenario: Scenario,
             on_step: Callable[[int, Step], None] | None = None) -> None:
        """Play ``scenario`` (:func:`gcs.app.play`); blocks until it ends."""
        play(scenario, self.app.loop, self.clock, on_step=on_step)

    def play_step(self, step: Step, *, where: str) -> None:
        """Play one step (:func:`gcs.app.play_step`); blocks until it is done."""
        play_step(step, self.app.loop, self.clock, where=where)

    def control(self, payload: bytes) -> str:
        """Send ``payload``, sealed with the team key, on the simulator's control key (a
        fault injected on purpose: ``sim._faults``); returns the simulator's answer
        (``queued``, or why it refused it), or ``sent`` to a free-running simulator
        joined; RuntimeError on real vehicles.

        To the simulator started here (or one joined in lockstep) it goes as a query,
        answered once the message is queued: sent by the playing thread in lockstep, it
        is then ahead of the tick's ack, so it acts at this tick's sim time on every run
        (a put could be overtaken by the ack: zenoh runs each subscriber on a thread of its
        own).
        """
        if self.real:
            raise RuntimeError("faults are injected into the simulator: not available on "
                               "real vehicles")
        topic = keys.sim(self.app.fleet, "control")
        if self._sealer is None:
            key = seal_key(self.team.config.gcs, Path(self.team.source).parent)
            self._sealer = Sealer(key, topic)
        sealed = self._sealer.seal(payload)
        if self.sim is None and not self.app.lockstep:
            self.app.session.put(topic, sealed)
            return "sent"
        for reply in self.app.session.get(topic, payload=sealed, timeout=CONTROL_ANSWER_S):
            if reply.ok is not None:
                return reply.ok.payload.to_bytes().decode(errors="replace")
        raise RuntimeError(f"the simulator did not answer a control message within "
                           f"{CONTROL_ANSWER_S:g} s")

    def land_before_exit(self, why: str = "the flight failed") -> str:
        """After a flight that failed on real vehicles (``why``: what ended it): the team,
        if in the air, is aborted (held, then landed, as the ABORT button) and waited for,
        with the loop running, before the GCS lets go of it: exiting at the failure would
        leave the copters in the air with no one streaming to them (ArduCopter in GUIDED
        hovers on). Returns what to add to the flight's error: how it ended."""
        loop = self.app.loop
        was = loop.phase
        if not (self.real and was.airborne):
            return ""
        if was not in (Phase.ABORTING, Phase.LANDING):
            loop.request(Action.ABORT)
        self._say(f"{why} with the team in the air ({was.text}): "
                  f"holding, then landing it before exiting (Ctrl-C to leave it to the "
                  f"autopilots)")
        deadline = time.monotonic() + LAND_BEFORE_EXIT_S
        while loop.phase.airborne:
            if time.monotonic() > deadline:
                return (f"; the team was still {loop.phase.text} {LAND_BEFORE_EXIT_S:g} s "
                        f"after it was aborted: left to the autopilots")
            time.sleep(0.1)
        self._say(f"the team is {loop.phase.text}")
        return f"; the team was aborted and is {loop.phase.text}"

    def stop_playing(self) -> None:
        """Leave the lockstep: the loop goes on without waiting for the playing thread."""
        if self._player == threading.get_ident():  # the participant is the thread's own
            self._playing.close()

    def figures(self, *, this_tick: bool = False) -> dict[str, object]:
        """The flight's figures so far, as ``gcs fly --json`` gives them (without its
        ``completed``, ``error`` and ``record``).

        ``this_tick``: count the tick whose window is open too. The metrics take a tick
        once its window closed; the playing thread, which runs inside the window, has
        seen that tick already (its phase, its state).
        """
        stats = self.app.loop.stats()
        loop = {"loop_stall_max_s": round(stats.stall_max, 3),
                "setpoint_gap_max_s": round(stats.setpoint_gap_max, 3),
                "recoveries": self.app.loop.recovery.attempts}
        wall = (self._wall_end if self._wall_end is not None else time.monotonic()) - self._wall0
        with self._metrics_lock:
            metrics, snap = self.metrics, self.app.loop.snapshot
            if this_tick and snap is not None and snap is not self._counted:
                metrics = copy.deepcopy(metrics)
                metrics.add(self._measured(snap))
            return metrics.to_json(wall_seconds=wall) | loop

    def simulator_exit(self) -> str | None:
        """`` (simulator exited: its last lines)`` if the simulator started here died."""
        if self.sim is None or self.sim.alive():
            return None
        return " (simulator exited: " + " | ".join(self.sim.stderr_tail[-3:]) + ")"

    def close(self) -> None:
        """Stop the loop, the GCS and the simulator started here; idempotent."""
        if self._closed:
            return
        self._closed = True
        try:
            self.stop_playing()
            self.app.close()
        finally:
            if self.sim is not None:
                self.sim.close()
            self._wall_end = time.monotonic()

    def __enter__(self) -> HeadlessFlight:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _refuse_unless_analysed(team: Team) -> None:
    """A ConfigError listing every violation when ``gcs analyze`` refuses ``team``: at
    once, before a simulator starts, not a flight that never gets ready."""
    result = analyze(team)
    if not result.ok:
        listed = " | ".join(f"{v.term}: {v.message}" for v in result.violations)
        raise ConfigError(team.source, "", f"gcs analyze refuses this team "
                          f"({len(result.violations)} violation(s); override_analysis flies "
                          f"it anyway): {listed}")


def fly(team: Team, scenario: Scenario, *, speed: str | None = None,
        record: Path | None = None, connect: str | None = None, progress: bool = True,
        override_analysis: bool = False, seed: int = 0,
        gusts: float | None = None, fork_server: bool = True) -> FlightResult:
    """Fly ``scenario``; blocks until it ends. ``speed``: of the sim (default ``"max"``;
    real vehicles: 1 only); ``connect``: endpoint of a running sim; ``seed``: of the
    started sim's sensor noise and gusts; ``gusts``: its turbulence, m/s per axis;
    ``fork_server``: as :class:`HeadlessFlight`'s. A
    team on px4/ardupilot links flies those (:class:`HeadlessFlight`); a bad ``speed``,
    ``connect`` or ``gusts`` for it is a ConfigError."""

    def say(line: str) -> None:
        if progress:
            print(f"gcs fly: {line}", file=sys.stderr, flush=True)

    error: str | None = None
    with HeadlessFlight(team, speed=speed, record=record, connect=connect, seed=seed,
                        override_analysis=override_analysis, say=say, gusts=gusts,
                        fork_server=fork_server) as flight:

        def show(k: int, step: Step) -> None:
            if progress:
                print(f"[t={flight.app.clock.now():7.2f} s] step {k + 1}/"
                      f"{len(scenario.steps)}: {step.describe()}", file=sys.stderr, flush=True)

        # In lockstep the scenario acts at ticks only, so every run is the same flight.
        flight.start()
        try:
            flight.play(scenario, on_step=show)
        except ScenarioError as exc:
            error = str(exc)
        except Exception as exc:  # the clock stopped, the sim died...
            error = f"{type(exc).__name__}: {exc}"
        except KeyboardInterrupt:
            if not flight.real:
                raise
            error = "interrupted (Ctrl-C)"
        flight.stop_playing()
        if error is not None:
            error += flight.land_before_exit()
        died = flight.simulator_exit()
        if died is not None:
            error = (error or "") + died
    return FlightResult(metrics=flight.figures(), error=error,
                        record=str(record) if record is not None else None)
