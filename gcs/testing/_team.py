"""A team flown from Python one call per step, simulated or real: :class:`Team`.

Why: ``gcs fly`` plays a YAML scenario and prints one JSON line; a test, or a
script flying a SITL team, wants its own assertions, loops and checks between
the steps. A :class:`Team` plays one scenario step per call
(:func:`gcs.app.play_step`) on a :class:`gcs.app.HeadlessFlight`, what ``gcs fly``
flies on, so a test and a scenario file fly the same way. :meth:`Team.connect`
flies the real autopilots a team file's ``links:`` reach, on the wall clock;
:class:`gcs.testing.SimTeam` is a Team on the simulator, in lockstep, with the
faults and the ground truth only a simulator has.
"""

from __future__ import annotations

import dataclasses
import threading
import warnings
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np

from gcs.app import (
    GcsApp,
    HeadlessFlight,
    Scenario,
    ScenarioError,
    Step,
    check_scenario,
    flies_real_vehicles,
)
from gcs.common import ConfigError, from_mapping
from gcs.config import Team as LoadedTeam
from gcs.config import load_team
from gcs.loop import ClockStoppedError, Phase, RuntimeSnapshot
from gcs.testing._metrics import Metrics
from gcs.wire import SimTruth

__all__ = ["FlightError", "FlightEvent", "SimulatorOnlyError", "Team", "TeamState"]


class FlightError(ScenarioError):
    """A call of :class:`Team` (or :class:`SimTeam`) that could not be done: the step and
    why, then the latest warnings of the flight."""


class SimulatorOnlyError(RuntimeError):
    """What only the simulator has (faults on command, ground truth), asked of real
    vehicles."""


class FlightEvent(Protocol):
    """An event of the flight, as the live page lists it."""

    @property
    def t(self) -> float:
        """Time on the flight's clock, s."""

    @property
    def level(self) -> str:
        """``info``, ``warning`` or ``error``."""

    @property
    def text(self) -> str:
        """What happened, one line."""


@dataclass(frozen=True)
class TeamState:
    """The team at one tick: what the GCS measured (telemetry, in the team frame) and, from
    the simulator, the ground truth (its world frame, which is the team frame: the
    simulated vehicles share one local frame). Arrays in formation order, NED, SI.

    On real vehicles (:meth:`Team.connect`) the ground truth properties raise
    :class:`SimulatorOnlyError`: nothing measures it there."""

    t: float
    """Time of the tick on the flight's clock, s."""
    ids: tuple[int, ...]
    phase: Phase
    p_ned: np.ndarray
    """(n, 3) positions the GCS flies on, m."""
    v_ned: np.ndarray
    """(n, 3) velocities the GCS flies on, m/s."""
    distance_errors: np.ndarray
    """(edges,) distance error of every edge of the formation (at the scale flown), m."""
    _truth: SimTruth | None = dataclasses.field(default=None, repr=False)
    simulated: bool = True
    """False on real vehicles: no ground truth."""

    @property
    def true_p_ned(self) -> np.ndarray | None:
        """(n, 3) true positions, m (None before the first truth sample)."""
        return self._true("true_p_ned", "vehicle_p_ned")

    @property
    def payload_p_ned(self) -> np.ndarray | None:
        """(3,) the payload's true position, m."""
        return self._true("payload_p_ned", "payload_p_ned")

    @property
    def payload_v_ned(self) -> np.ndarray | None:
        """(3,) the payload's true velocity, m/s."""
        return self._true("payload_v_ned", "payload_v_ned")

    @property
    def rope_tension(self) -> np.ndarray | None:
        """(n,) tension of each vehicle's rope, N."""
        return self._true("rope_tension", "rope_tension")

    def _true(self, name: str, field: str) -> np.ndarray | None:
        if not self.simulated:
            raise SimulatorOnlyError(f"TeamState.{name}: ground truth comes from the "
                                     f"simulator, not available on real vehicles")
        return None if self._truth is None else np.array(getattr(self._truth, field))

    @classmethod
    def of(cls, snap: RuntimeSnapshot, *, simulated: bool = True) -> TeamState:
        fleet = snap.fleet
        return cls(t=fleet.t, ids=fleet.ids, phase=snap.phase, p_ned=fleet.p_ned.copy(),
                   v_ned=fleet.v_ned.copy(), distance_errors=snap.distance_errors.copy(),
                   _truth=snap.truth if simulated else None, simulated=simulated)


class Team:
    """A team and a headless GCS flying it, one call per step.

    Every call that flies blocks until it is done, in the flight's seconds (sim
    seconds; wall seconds on real vehicles), or raises :class:`FlightError`
    naming the step and the latest warnings; a bad argument is a one-line
    ``ValueError`` (:class:`gcs.common.ConfigError`). Close it (a ``with`` block)
    to stop the GCS and every port it opened; a test that raises closes it too.

    Made by :meth:`connect` (real autopilots) or as a :class:`SimTeam` (the
    simulator). On real vehicles the faults (:meth:`cut_link`, :meth:`kill`,
    :meth:`gust`) and the ground truth raise :class:`SimulatorOnlyError`.
    """

    def __init__(self, flight: HeadlessFlight) -> None:
        """Start ``flight`` and wait for its first tick (use :meth:`connect` or SimTeam)."""
        self.team = flight.team
        self._owner = threading.get_ident()
        self._flight = flight
        # a team left unclosed is closed when collected or at exit (a simulator dies with
        # this process anyway: PR_SET_PDEATHSIG)
        self._finalizer = weakref.finalize(self, flight.close)
        try:
            flight.start()
            # in lockstep, the test starts at the first tick on every run; else once ticking
            if not flight.app.gate.pause():
                self._until(lambda: flight.app.loop.snapshot is not None, 30.0,
                            "the first tick")
        except BaseException:
            self.close()
            raise

    @staticmethod
    def connect(config: str | Path | LoadedTeam, *, record: str | Path | None = None,
                override_analysis: bool = False) -> Team:
        """Fly the real autopilots ``config``'s ``links:`` reach (px4 or ardupilot
        profiles: vehicles, their SITL, or ``gcs sim --udp``), as ``gcs run`` would:
        no simulator, the wall clock. Returns once the GCS ticks; :meth:`arm` waits for
        every vehicle to be heard from and to pass the checks before arming.

        Args:
            config: team file (or a loaded :class:`gcs.config.Team`) with ``links:``.
            record: .tlog file to record the flight to (``gcs report`` reads it).
            override_analysis: fly a team that ``gcs analyze`` refuses.
        """
        team = config if isinstance(config, LoadedTeam) else load_team(config)
        if not flies_real_vehicles(team):
            raise ConfigError(team.source, "links", "no px4 or ardupilot link: "
                              "Team.connect flies real autopilots; fly a simulated team "
                              "with SimTeam")
        return Team(HeadlessFlight(team, record=None if record is None else Path(record),
                                   override_analysis=override_analysis))

    # -- the flight -----------------------------------------------------------------------

    def arm(self, *, timeout: float = 120.0) -> None:
        """Arm every vehicle, once the pre-flight checks pass (phase *armed*)."""
        self._play("arm", {"action": "arm", "timeout": timeout})

    def takeoff(self, *, timeout: float = 120.0) -> None:
        """Take off to the hover above the payload (phase *hover*)."""
        self._play("takeoff", {"action": "takeoff", "timeout": timeout})

    def lift(self, *, timeout: float = 120.0) -> None:
        """Lift the payload and fly in formation (phase *formation*)."""
        self._play("lift", {"action": "lift", "timeout": timeout})

    def set_down(self, *, timeout: float = 120.0) -> None:
        """Set the payload down (back to *hover*)."""
        self._play("set_down", {"action": "set_down", "timeout": timeout})

    def land(self, *, timeout: float = 120.0) -> None:
        """Land and disarm (phase *landed*)."""
        self._play("land", {"action": "land", "timeout": timeout})

    def abort(self, *, timeout: float = 120.0) -> None:
        """Abort: hold, then land (phase *landed*)."""
        self._play("abort", {"action": "abort", "timeout": timeout})

    def resume(self, *, timeout: float = 120.0) -> None:
        """Bring vehicles that fell into HOLD back to the GCS's setpoints."""
        self._play("resume", {"action": "resume", "timeout": timeout})

    def sticks(self, forward: float = 0.0, right: float = 0.0, rotate: float = 0.0, *,
               seconds: float, timeout: float = 120.0) -> None:
        """Hold the sticks (each in [-1, 1]) until the team has flown them ``seconds`` of
        the flight's time, then centre them. Time in which the motion was frozen (a stale
        vehicle, one out of its mode) does not count; frozen for ``timeout``: FlightError."""
        self._play("sticks", {"sticks": {"forward": forward, "right": right, "rotate": rotate},
                              "duration": seconds, "timeout": timeout})

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` of the flight's time pass, sticks centred (FlightError if the
        flight was aborted meanwhile)."""
        self._play("wait", {"wait": seconds})

    def scale(self, scale: float) -> None:
        """Grow or shrink the shape to ``scale`` times the team file's (from the next tick
        on; the team takes a while to get there: :meth:`wait`)."""
        self._play("scale", {"scale": scale}, checked=True)

    def altitude(self, altitude: float) -> None:
        """Climb or descend to ``altitude`` m above the ground (from the next tick on)."""
        self._play("altitude", {"altitude": altitude}, checked=True)

    def wait_for(self, phase: Phase | str, *, timeout: float = 120.0) -> None:
        """Wait until the team is in ``phase`` (a :class:`gcs.loop.Phase` or its text, e.g.
        ``"landed"``), at most ``timeout`` s of the flight's time: after a fault, the
        landing."""
        want = phase if isinstance(phase, Phase) else _phase_named(phase)
        self._until(lambda: self.phase is want, timeout, f"wait_for({want.text!r})")

    # -- faults: the simulator's (SimTeam) ---------------------------------------------------

    def cut_link(self, sysid: int, seconds: float | None = None) -> None:
        """Silence a vehicle's radio (:meth:`SimTeam.cut_link`): simulator only."""
        raise self._simulator_only("cut_link")

    def restore_link(self, sysid: int) -> None:
        """End a cut (:meth:`SimTeam.restore_link`): simulator only."""
        raise self._simulator_only("restore_link")

    def kill(self, sysid: int) -> None:
        """A vehicle dies now (:meth:`SimTeam.kill`): simulator only."""
        raise self._simulator_only("kill")

    def gust(self, wind_ned: Sequence[float], seconds: float) -> None:
        """More wind for a while (:meth:`SimTeam.gust`): simulator only."""
        raise self._simulator_only("gust")

    # -- what the test reads --------------------------------------------------------------

    @property
    def time(self) -> float:
        """The flight's clock, s: sim time, or wall seconds since the GCS started on real
        vehicles."""
        return self._flight.app.clock.now()

    @property
    def phase(self) -> Phase:
        """The flight phase as of the last tick."""
        return self._snapshot().phase

    @property
    def events(self) -> tuple[FlightEvent, ...]:
        """Every event so far (phases, warnings, errors), oldest first."""
        return self._flight.app.loop.events()

    def state(self) -> TeamState:
        """The team as of the last tick: measured, and the simulator's truth."""
        return TeamState.of(self._snapshot(), simulated=not self._flight.real)

    def metrics(self) -> Metrics:
        """The flight's figures so far: those of ``gcs fly --json``, as attributes (those of
        the payload and the ropes None on real vehicles: nothing measures them)."""
        return Metrics.from_json(self._flight.figures(this_tick=True))

    @property
    def app(self) -> GcsApp:
        """The GCS flying the team (its runtime, links, operator), for what this class
        does not offer."""
        return self._flight.app

    # -- closing --------------------------------------------------------------------------

    def close(self) -> None:
        """Stop the GCS (and a simulator started for it) and close their ports; idempotent.

        Real vehicles still in the air (a test that failed, or forgot to land) are
        aborted and landed first (up to 120 s, as ``gcs fly`` does after a failed
        flight): the GCS never lets go of a flying team."""
        if self._finalizer.alive:
            try:
                self._flight.land_before_exit("closed")
            finally:
                self._finalizer()

    def __enter__(self) -> Team:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- helpers --------------------------------------------------------------------------

    def _play(self, what: str, fields: dict[str, object], *, checked: bool = False) -> None:
        """Play one step (built and checked as a scenario file's would be)."""
        source = f"{type(self).__name__}.{what}"
        step = from_mapping(Step, fields, source)
        if checked:
            scenario = Scenario(name=source, steps=(step,))
            for warning in check_scenario(scenario, self.team, source):
                warnings.warn(warning, stacklevel=3)
        self._flying()
        try:
            self._flight.play_step(step, where=f"{what}()")
        except ScenarioError as exc:
            raise FlightError(f"{exc}{self._warnings(str(exc))}") from None
        except ClockStoppedError as exc:
            raise FlightError(self._stopped(f"{what}()", exc)) from None

    def _until(self, done: Callable[[], bool], timeout: float, what: str) -> None:
        """Let ticks pass until ``done()``; FlightError after ``timeout`` s of the flight's
        time."""
        self._flying()
        clock = self._flight.clock
        start = clock.now()
        period = self._flight.app.loop.period
        try:
            while not done():
                if clock.now() - start > timeout:
                    raise FlightError(f"{what}: not done after {timeout:g} s (phase "
                                      f"{self.phase.text}){self._warnings('')}")
                clock.sleep_until(clock.now() + period / 2)
        except ClockStoppedError as exc:
            raise FlightError(self._stopped(what, exc)) from None

    def _simulator_only(self, what: str) -> SimulatorOnlyError:
        return SimulatorOnlyError(f"{what}: a fault injected into the simulator, not "
                                  f"available on real vehicles ({self.team.source}'s links)")

    def _snapshot(self) -> RuntimeSnapshot:
        snap = self._flight.app.loop.snapshot
        assert snap is not None, "the constructor waits for the first tick"
        return snap

    def _flying(self) -> None:
        name = type(self).__name__
        if not self._finalizer.alive:
            raise RuntimeError(f"this {name} is closed")
        if threading.get_ident() != self._owner:
            raise RuntimeError(f"a {name} is flown by the thread that made it (its steps act "
                               f"at the lockstep's ticks)")

    def _warnings(self, said: str) -> str:
        """``; latest warnings: ...``: the last three not already in ``said``."""
        latest = [e.text for e in self.events if e.level != "info" and e.text not in said]
        return f"; latest warnings: {' | '.join(latest[-3:])}" if latest else ""

    def _stopped(self, what: str, exc: ClockStoppedError) -> str:
        return f"{what}: {exc}{self._flight.simulator_exit() or ''}{self._warnings(str(exc))}"


def _phase_named(text: str) -> Phase:
    for phase in Phase:
        if phase.text == text or phase.name.lower() == text.lower():
            return phase
    raise ValueError(f"no phase {text!r} (one of {', '.join(p.text for p in Phase)})")
