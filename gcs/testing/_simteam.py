"""A simulated team flown from Python, for integration tests: :class:`SimTeam`.

Why: ``gcs fly`` plays a YAML scenario and prints one JSON line; a test wants
its own assertions, loops and faults between the steps. A :class:`SimTeam`
starts the simulator and a headless GCS in lockstep on the simulator's clock
(:class:`gcs.app.HeadlessFlight`, what ``gcs fly`` flies on) and plays one
scenario step per call (:func:`gcs.app.play_step`), so a test and a scenario
file fly the same way. In lockstep the simulated world stands still while the
test's own code runs between two calls, so every run of a seed is the same
flight, whatever the machine's load.
"""

from __future__ import annotations

import json
import math
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
)
from gcs.common import from_mapping
from gcs.config import Team, load_team
from gcs.loop import ClockStoppedError, Phase, RuntimeSnapshot
from gcs.testing._metrics import Metrics

__all__ = ["FlightError", "FlightEvent", "SimTeam", "TeamState"]

GUST_MAX_M_S = 30.0
"""Largest gust per axis the simulator takes, m/s (``sim._faults.GUST_MAX_M_S``)."""

FAULT_MAX_S = 3600.0
"""Longest timed cut or gust the simulator takes, s (``sim._faults.FAULT_MAX_S``)."""


class FlightError(ScenarioError):
    """A call of :class:`SimTeam` that could not be done: the step and why, then the
    latest warnings of the flight."""


class FlightEvent(Protocol):
    """An event of the flight, as the live page lists it."""

    @property
    def t(self) -> float:
        """Sim time, s."""

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
    simulated vehicles share one local frame). Arrays in formation order, NED, SI."""

    t: float
    """Sim time of the tick, s."""
    ids: tuple[int, ...]
    phase: Phase
    p_ned: np.ndarray
    """(n, 3) positions the GCS flies on, m."""
    v_ned: np.ndarray
    """(n, 3) velocities the GCS flies on, m/s."""
    distance_errors: np.ndarray
    """(edges,) distance error of every edge of the formation (at the scale flown), m."""
    true_p_ned: np.ndarray | None
    """(n, 3) true positions, m (None before the first truth sample)."""
    payload_p_ned: np.ndarray | None
    payload_v_ned: np.ndarray | None
    rope_tension: np.ndarray | None
    """(n,) tension of each vehicle's rope, N."""

    @classmethod
    def of(cls, snap: RuntimeSnapshot) -> TeamState:
        truth, fleet = snap.truth, snap.fleet
        return cls(t=fleet.t, ids=fleet.ids, phase=snap.phase, p_ned=fleet.p_ned.copy(),
                   v_ned=fleet.v_ned.copy(), distance_errors=snap.distance_errors.copy(),
                   true_p_ned=None if truth is None else np.array(truth.vehicle_p_ned),
                   payload_p_ned=None if truth is None else np.array(truth.payload_p_ned),
                   payload_v_ned=None if truth is None else np.array(truth.payload_v_ned),
                   rope_tension=None if truth is None else np.array(truth.rope_tension))


class SimTeam:
    """A simulated team and a headless GCS flying it, one call per step.

    Every call that flies blocks until it is done, in sim seconds, or raises
    :class:`FlightError` naming the step and the latest warnings; a bad argument
    is a one-line ``ValueError`` (:class:`gcs.common.ConfigError`). Close it (a
    ``with`` block, or the ``sim_team`` pytest fixture) to stop the simulator,
    the GCS and every port they opened; a test that raises closes it too.

    Args:
        config: team file (or a loaded :class:`gcs.config.Team`).
        seed: of the simulator's sensor noise and gusts: one seed, one flight.
        speed: sim seconds per wall second, or ``"max"``: as fast as the machine goes.
        record: .tlog file to record the flight to (``gcs report`` reads it).
        lockstep: the GCS acknowledges every tick (repeatable); False lets the simulator
            run on its own at ``speed`` (a number), as a real team would.
        insecure: fly unsigned (``gcs fly --insecure``).
        override_analysis: fly a team that ``gcs analyze`` refuses.
        start_timeout: longest wall time the simulator may take to come up, s (about 6 s
            on a quiet machine, over a minute on a loaded one).
    """

    def __init__(self, config: str | Path | Team, *, seed: int = 0,
                 speed: float | str = "max", record: str | Path | None = None,
                 lockstep: bool = True, insecure: bool = False,
                 override_analysis: bool = False, start_timeout: float = 300.0) -> None:
        team = config if isinstance(config, Team) else load_team(config)
        if insecure:
            team = team.without_signing()
        self.team = team
        self._owner = threading.get_ident()
        self._flight = HeadlessFlight(
            team, speed=_speed(speed, lockstep), record=None if record is None else Path(record),
            seed=_whole(seed, "seed"), override_analysis=override_analysis, lockstep=lockstep,
            ready_timeout=start_timeout)
        # a team left unclosed is closed when collected or at exit (the simulator dies with
        # this process anyway: PR_SET_PDEATHSIG)
        self._finalizer = weakref.finalize(self, self._flight.close)
        try:
            self._flight.start()
            # in lockstep, the test starts at the first tick on every run; else once ticking
            if not self._flight.app.gate.pause():
                self._until(lambda: self._flight.app.loop.snapshot is not None, 30.0,
                            "the first tick")
        except BaseException:
            self.close()
            raise

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
        sim time, then centre them. Time in which the motion was frozen (a stale
        vehicle, one out of its mode) does not count; frozen for ``timeout``: FlightError."""
        self._play("sticks", {"sticks": {"forward": forward, "right": right, "rotate": rotate},
                              "duration": seconds, "timeout": timeout})

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` of sim time pass, sticks centred (FlightError if the flight was
        aborted meanwhile)."""
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
        ``"landed"``), at most ``timeout`` s of sim time: after a fault, the landing."""
        want = phase if isinstance(phase, Phase) else _phase_named(phase)
        self._until(lambda: self.phase is want, timeout, f"wait_for({want.text!r})")

    # -- faults ---------------------------------------------------------------------------

    def cut_link(self, sysid: int, seconds: float | None = None) -> None:
        """Silence vehicle ``sysid``'s radio both ways from this tick on, for ``seconds`` of
        sim time (the simulator restores it then) or until :meth:`restore_link`. The
        vehicle flies its own failsafe meanwhile (HOLD, then LAND). Returns at once."""
        self._fault({"action": "cut", "sysid": self._vehicle(sysid)}
                    | ({} if seconds is None else {"seconds": _duration(seconds)}))

    def restore_link(self, sysid: int) -> None:
        """End a cut of vehicle ``sysid``'s link now."""
        self._fault({"action": "restore", "sysid": self._vehicle(sysid)})

    def kill(self, sysid: int) -> None:
        """Vehicle ``sysid`` dies now: its link and liveliness go, its motors stop."""
        self._fault({"action": "kill", "sysid": self._vehicle(sysid)})

    def gust(self, wind_ned: Sequence[float], seconds: float) -> None:
        """Add ``wind_ned`` (m/s, NED: north, east, down) to the simulator's wind, on every
        vehicle and the payload, from this tick for ``seconds`` of sim time. Returns at
        once."""
        wind = [float(w) for w in wind_ned]
        if len(wind) != 3 or not all(math.isfinite(w) and abs(w) <= GUST_MAX_M_S
                                     for w in wind):
            raise ValueError(f"gust: wind_ned must be 3 numbers within ±{GUST_MAX_M_S:g} m/s, "
                             f"got {list(wind_ned)!r}")
        self._fault({"action": "gust", "sysid": 0, "ned": wind, "seconds": _duration(seconds)})

    # -- what the test reads --------------------------------------------------------------

    @property
    def time(self) -> float:
        """Sim time, s."""
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
        return TeamState.of(self._snapshot())

    def metrics(self) -> Metrics:
        """The flight's figures so far: those of ``gcs fly --json``, as attributes."""
        return Metrics.from_json(self._flight.figures(this_tick=True))

    @property
    def app(self) -> GcsApp:
        """The GCS flying the team (its runtime, links, operator), for what this class
        does not offer."""
        return self._flight.app

    @property
    def endpoint(self) -> str:
        """The zenoh endpoint the simulator listens on."""
        return self._flight.endpoint

    # -- closing --------------------------------------------------------------------------

    def close(self) -> None:
        """Stop the GCS and the simulator and close their ports; idempotent."""
        self._finalizer()

    def __enter__(self) -> SimTeam:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- helpers --------------------------------------------------------------------------

    def _play(self, what: str, fields: dict[str, object], *, checked: bool = False) -> None:
        """Play one step (built and checked as a scenario file's would be)."""
        source = f"SimTeam.{what}"
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
        """Let ticks pass until ``done()``; FlightError after ``timeout`` s of sim time."""
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

    def _fault(self, command: dict[str, object]) -> None:
        self._flying()
        answer = self._flight.control(json.dumps(command).encode())
        if answer.startswith("refused"):
            raise FlightError(f"{command['action']}: the simulator {answer}")

    def _vehicle(self, sysid: int) -> int:
        ids = self.team.formation.ids
        if isinstance(sysid, bool) or not isinstance(sysid, int) or sysid not in ids:
            raise ValueError(f"no vehicle {sysid!r} in {self.team.source} (vehicles "
                             f"{', '.join(str(i) for i in ids)})")
        return sysid

    def _snapshot(self) -> RuntimeSnapshot:
        snap = self._flight.app.loop.snapshot
        assert snap is not None, "the constructor waits for the first tick"
        return snap

    def _flying(self) -> None:
        if not self._finalizer.alive:
            raise RuntimeError("this SimTeam is closed")
        if threading.get_ident() != self._owner:
            raise RuntimeError("a SimTeam is flown by the thread that made it (its steps act "
                               "at the lockstep's ticks)")

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


def _speed(speed: float | str, lockstep: bool) -> str:
    if speed == "max":
        if not lockstep:
            raise ValueError("speed='max' needs lockstep: a simulator running free as fast "
                             "as it can leaves the GCS behind (late ticks, stale telemetry)")
        return "max"
    if isinstance(speed, bool) or not isinstance(speed, int | float) \
            or not (math.isfinite(speed) and speed > 0):
        raise ValueError(f"speed must be a positive number or 'max', got {speed!r}")
    return f"{float(speed):g}"


def _whole(value: int, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"{name} must be a whole number >= 0, got {value!r}")
    return value


def _duration(seconds: float) -> float:
    if isinstance(seconds, bool) or not isinstance(seconds, int | float) \
            or not (math.isfinite(seconds) and 0.0 < seconds <= FAULT_MAX_S):
        raise ValueError(f"seconds must be above 0 and at most {FAULT_MAX_S:g}, "
                         f"got {seconds!r}")
    return float(seconds)
