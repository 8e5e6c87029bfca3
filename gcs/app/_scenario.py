"""Scripted operator inputs: a scenario is a list of steps played through the same
operator-command object and phase actions as the browser and the gamepad.

A step does one thing:

* ``action: arm|takeoff|lift|set_down|land|abort|resume`` and waits until the
  phase the action leads to is done (takeoff: hover; lift: formation; set_down:
  hover; land: landed; resume keeps the phase: until it has run), at most
  ``timeout`` seconds;
* ``sticks: {forward, right, rotate}`` held until the team has flown them for
  ``duration`` seconds (re-sent every tick, like a hand on a stick): time in
  which the motion was frozen (a vehicle out of its mode, stale telemetry) or
  held does not count, and a step not flown within ``timeout`` fails, so a
  headless flight never reports motions it did not fly;
* ``scale: 1.2`` or ``scale_steps: +2``; ``altitude: 1.8`` or ``altitude_steps: -1``;
* ``wait: 3`` seconds with the sticks centred.

All times are on the loop's clock (simulated seconds in a headless flight), each
at most an hour. A scenario is loaded on its own (:func:`load_scenario`) and checked
against the team it flies (:func:`check_scenario`): a scale or an altitude outside
the team's ranges is refused, not clipped in flight.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from gcs.analysis import Analysis, analyze, safe_guidance
from gcs.common import ConfigError, FieldError, field, from_mapping, load_yaml
from gcs.config import GuidanceConfig, Team
from gcs.loop import Action, Clock, Phase, Runtime

__all__ = ["Scenario", "ScenarioError", "Step", "Sticks", "check_scenario", "load_scenario",
           "play", "play_step", "scenario_scales"]

LONGEST_S = 3600.0
"""Longest wait, stick hold or timeout of one step, s: a scenario is a test flight."""

#: The phase an action is finished in.
DONE_IN = {
    Action.ARM: Phase.ARMED,
    Action.DISARM: Phase.READY,
    Action.TAKEOFF: Phase.HOVER,
    Action.LIFT: Phase.FORMATION,
    Action.SET_DOWN: Phase.HOVER,
    Action.LAND: Phase.LANDED,
    Action.ABORT: Phase.LANDED,
}


class ScenarioError(RuntimeError):
    """A step that could not be completed; names the step."""


@dataclass(frozen=True)
class Sticks:
    """Raw stick positions in [-1, 1]."""

    forward: float = field(doc="forward stick", default=0.0, ge=-1.0, le=1.0)
    right: float = field(doc="right stick", default=0.0, ge=-1.0, le=1.0)
    rotate: float = field(doc="rotation stick (positive: clockwise from above)", default=0.0,
                          ge=-1.0, le=1.0)


@dataclass(frozen=True)
class Step:
    """One step of a scenario (exactly one of the kinds)."""

    action: str | None = field(doc="arm, takeoff, lift, set_down, land, abort, resume",
                               default=None)
    sticks: Sticks | None = field(doc="stick positions held for `duration`", default=None)
    duration: float = field(doc="how long sticks are held, s", default=0.0, ge=0.0,
                            le=LONGEST_S)
    scale: float | None = field(doc="shape scale", default=None, gt=0.0)
    scale_steps: int | None = field(doc="grow (+) or shrink (-) by steps", default=None)
    altitude: float | None = field(doc="altitude target above the ground, m", default=None,
                                   ge=0.0)
    altitude_steps: int | None = field(doc="raise (+) or lower (-) by steps", default=None)
    wait: float | None = field(doc="wait with sticks centred, s", default=None, ge=0.0,
                               le=LONGEST_S)
    timeout: float = field(doc="longest wait for an action's phase, s", default=120.0, gt=0.0,
                           le=LONGEST_S)
    label: str = field(doc="name shown in progress and errors", default="")

    def __post_init__(self) -> None:
        kinds = [k for k in ("action", "sticks", "scale", "scale_steps", "altitude",
                             "altitude_steps", "wait") if getattr(self, k) is not None]
        if len(kinds) != 1:
            raise ValueError(f"a step does exactly one thing, got {kinds or 'nothing'}")
        if self.action is not None and self.action not in {a.value for a in Action}:
            raise ValueError(f"action: unknown {self.action!r} (one of "
                             f"{', '.join(a.value for a in Action)})")
        if self.sticks is not None and self.duration <= 0.0:
            raise FieldError("duration", "sticks are held for a duration: give one above 0 s")
        if self.sticks is None and self.duration != 0.0:
            raise FieldError("duration", f"only a sticks step is held for a duration, this "
                                         f"step is {kinds[0]}")

    def describe(self) -> str:
        if self.label:
            return self.label
        for k in ("action", "scale", "scale_steps", "altitude", "altitude_steps", "wait"):
            value = getattr(self, k)
            if value is not None:
                return f"{k} {value}"
        s = self.sticks
        assert s is not None
        return f"sticks ({s.forward:+.2f}, {s.right:+.2f}, {s.rotate:+.2f}) for {self.duration:g} s"


@dataclass(frozen=True)
class Scenario:
    """A named list of steps."""

    name: str = field(doc="scenario name")
    steps: tuple[Step, ...] = field(doc="the steps, played in order", min_len=1)


def load_scenario(path: str | Path) -> Scenario:
    """Load and validate a scenario file (one-line ConfigError on any mistake)."""
    raw = load_yaml(path)
    if isinstance(raw, dict) and isinstance(raw.get("steps"), list):
        # the step kinds are validated by Step; report their index in the file
        for k, step in enumerate(raw["steps"]):
            if not isinstance(step, dict):
                raise ConfigError(str(path), f"steps[{k}]", "expected a mapping")
    return from_mapping(Scenario, raw, str(path))


def _scales_asked(scenario: Scenario, scale_step: float) -> Iterator[tuple[int, float]]:
    """(step index, the scale it asks) for each step that sets the scale, from 1."""
    scale = 1.0
    for k, step in enumerate(scenario.steps):
        if step.scale is not None:
            scale = step.scale
        elif step.scale_steps is not None:
            scale = round(scale + step.scale_steps * scale_step, 6)
        else:
            continue
        yield k, scale


def scenario_scales(scenario: Scenario, guidance: GuidanceConfig) -> tuple[float, ...]:
    """The smallest and largest scales ``scenario`` flies with ``guidance`` (the one flown:
    :func:`gcs.analysis.safe_guidance`), and 1, sorted."""
    asked = [scale for _, scale in _scales_asked(scenario, guidance.scale_step)]
    held = [min(max(scale, guidance.scale_min), guidance.scale_max) for scale in asked]
    return tuple(sorted({1.0, min(held), max(held)} if held else {1.0}))


def check_scenario(scenario: Scenario, team: Team, source: str, *,
                   analysis: Analysis | None = None) -> list[str]:
    """Refuse a scenario that asks ``team`` for what its config does not allow; returns
    warnings for what the flight will fly otherwise than asked.

    A scale outside ``guidance.scale_min..scale_max`` (given, or reached by
    ``scale_steps`` from 1) or an altitude outside
    ``operator.altitude_min..altitude_max`` raises ConfigError naming ``source`` and
    the step; in flight the operator command would clip it silently. A scale within
    the config but outside what the analysis certifies (the GCS holds it there:
    :func:`gcs.analysis.safe_guidance`) is a warning naming the scale flown.
    """
    g, op = team.config.guidance, team.config.operator
    flown = safe_guidance(team, analysis or analyze(team))
    safe_min, safe_max = flown.scale_min, flown.scale_max
    warnings: list[str] = []
    scales = dict(_scales_asked(scenario, g.scale_step))
    for k, step in enumerate(scenario.steps):
        where = f"steps[{k}]"
        if k in scales:
            given = step.scale is not None
            scale = scales[k]
            what = f"{scale:g}" if given else f"takes the scale to {scale:g}, which"
            at = f"{where}.scale" if given else f"{where}.scale_steps"
            if scale < g.scale_min - 1e-9:
                raise ConfigError(source, at, f"{what} is below guidance.scale_min "
                                  f"{g.scale_min:g} of {team.source}")
            if scale > g.scale_max + 1e-9:
                raise ConfigError(source, at, f"{what} is above guidance.scale_max "
                                  f"{g.scale_max:g} of {team.source}")
            if scale > safe_max + 1e-9:
                warnings.append(f"{source}: {at}: {what} is above {safe_max:.4f}, the largest "
                                f"scale the analysis' safe deformation allows for "
                                f"{team.source}; the GCS flies {safe_max:.4f}")
            if scale < safe_min - 1e-9:
                warnings.append(f"{source}: {at}: {what} is below {safe_min:.4f}, the smallest "
                                f"scale at which the analysis' accelerating payload loads no "
                                f"vehicle to its reference thrust for {team.source}; the GCS "
                                f"flies {safe_min:.4f}")
        elif step.altitude is not None:
            if step.altitude < op.altitude_min:
                raise ConfigError(source, f"{where}.altitude", f"{step.altitude:g} m is below "
                                  f"operator.altitude_min {op.altitude_min:g} m of "
                                  f"{team.source}")
            if step.altitude > op.altitude_max:
                raise ConfigError(source, f"{where}.altitude", f"{step.altitude:g} m is above "
                                  f"operator.altitude_max {op.altitude_max:g} m of "
                                  f"{team.source}")
    return warnings


def play(scenario: Scenario, runtime: Runtime, clock: Clock, *,
         on_step: Callable[[int, Step], None] | None = None) -> None:
    """Play every step in order; ScenarioError names the step that failed."""
    for k, step in enumerate(scenario.steps):
        if on_step is not None:
            on_step(k, step)
        play_step(step, runtime, clock, where=f"step {k + 1} ({step.describe()})")


def play_step(step: Step, runtime: Runtime, clock: Clock, *, where: str) -> None:
    """Play one step (a scenario's, or one call of :class:`gcs.testing.SimTeam`); returns when
    it is done, or raises ScenarioError starting with ``where``."""
    op = runtime.operator
    now = clock.now()
    if step.action is not None:
        action = Action(step.action)
        if _phase(runtime) is Phase.CONNECT:
            _wait_ready(runtime, clock, step.timeout, where)
        try:
            runtime.request(action)
        except Exception as exc:
            raise ScenarioError(f"{where}: {exc}") from None
        if action in DONE_IN:
            _wait_phase(runtime, clock, DONE_IN[action], step.timeout, where)
        else:  # resume: the phase stays
            _wait_action(runtime, clock, step.timeout, where)
    elif step.sticks is not None:
        _hold_sticks(runtime, clock, step.sticks, step.duration, step.timeout, where)
    elif step.scale is not None:
        op.set_scale(step.scale)
    elif step.scale_steps is not None:
        op.step_scale(step.scale_steps)
    elif step.altitude is not None:
        op.set_altitude(step.altitude, now=now)
    elif step.altitude_steps is not None:
        op.step_altitude(step.altitude_steps, now=now)
    elif step.wait is not None:
        clock.sleep_until(now + step.wait)
        _check_not_aborted(runtime, where)


def _hold_sticks(runtime: Runtime, clock: Clock, sticks: Sticks, duration: float,
                 timeout: float, where: str) -> None:
    """Hold the sticks until the loop has flown them for ``duration`` (ticks whose motion was
    frozen do not count); ScenarioError after ``timeout`` of frozen motion."""
    op, period = runtime.operator, runtime.period
    start = t = clock.now()
    flown = 0.0
    while flown < duration - 1e-9:
        op.set_sticks(sticks.forward, sticks.right, sticks.rotate, now=t, source="scenario")
        step = min(period, duration - flown)
        t = clock.now() + step
        clock.sleep_until(t)
        _check_not_aborted(runtime, where)
        snap = runtime.snapshot
        if snap is not None and snap.moving:
            flown += step
        elif snap is not None and snap.phase is not Phase.FORMATION:
            raise ScenarioError(f"{where}: sticks move the team in formation flight only "
                                f"(phase: {snap.phase.text}; lift first)")
        elif clock.now() - start - flown > timeout:
            raise ScenarioError(f"{where}: the motion was frozen for {timeout:g} s"
                                f"{_last_warning(runtime)}")
    op.release(now=clock.now(), source="scenario")


def _last_warning(runtime: Runtime) -> str:
    """`` (the latest warning or error)``, or nothing."""
    last = [e.text for e in runtime.events() if e.level != "info"]
    return f" ({last[-1]})" if last else ""


def _phase(runtime: Runtime) -> Phase:
    """The phase as of the last tick.

    Why not the live one: in lockstep the phase actions run in the tick's window
    beside the scenario, so what the live phase shows at a given moment of that
    window depends on thread timing; the last tick's does not.
    """
    snap = runtime.snapshot
    return snap.phase if snap is not None else runtime.phase


def _check_not_aborted(runtime: Runtime, where: str) -> None:
    if _phase(runtime) in (Phase.ABORTING, Phase.LANDING):
        raise ScenarioError(f"{where}: the flight was aborted{_last_warning(runtime)}")


def _wait_ready(runtime: Runtime, clock: Clock, timeout: float, where: str) -> None:
    """Wait for the pre-flight checks (every vehicle present and fresh, analysis passes)."""
    start = clock.now()
    while _phase(runtime) is Phase.CONNECT:
        if clock.now() - start > timeout:
            fleet = runtime.snapshot.fleet if runtime.snapshot is not None else None
            silent = [] if fleet is None else [
                vid for vid, age in zip(fleet.ids, fleet.age, strict=True) if not age < 1.0]
            warnings = [e.text for e in runtime.events() if e.level != "info"]
            why = (f"vehicles {silent} not heard from" if silent else
                   warnings[-1] if warnings else "pre-flight checks did not pass")
            raise ScenarioError(f"{where}: not ready after {timeout:g} s: {why}")
        clock.sleep_until(clock.now() + runtime.period)


def _wait_action(runtime: Runtime, clock: Clock, timeout: float, where: str) -> None:
    """Wait until the phase action started last has run (an error ends the scenario)."""
    start = clock.now()
    seen_errors = runtime.errors
    while True:
        if runtime.errors > seen_errors:
            last = [e.text for e in runtime.events() if e.level == "error"]
            raise ScenarioError(f"{where}: {last[-1] if last else 'the action failed'}")
        if not runtime.action_running:
            return
        if clock.now() - start > timeout:
            raise ScenarioError(f"{where}: still running after {timeout:g} s")
        clock.sleep_until(clock.now() + runtime.period)


def _wait_phase(runtime: Runtime, clock: Clock, phase: Phase, timeout: float,
                where: str) -> None:
    start = clock.now()
    seen_errors = runtime.errors
    while _phase(runtime) is not phase:
        if runtime.errors > seen_errors:
            last = [e.text for e in runtime.events() if e.level == "error"]
            raise ScenarioError(f"{where}: {last[-1] if last else 'an action failed'}")
        if clock.now() - start > timeout:
            raise ScenarioError(f"{where}: still {_phase(runtime).text} after {timeout:g} s "
                                f"(waiting for {phase.text})")
        clock.sleep_until(clock.now() + runtime.period)
