"""Monte-Carlo flights: one scenario flown once per simulator seed, and the spread of each
figure over them (``gcs fly --seeds``, :func:`fly_seeds`).

Why: one lockstep flight is one draw of the simulator's sensor noise and gusts; a
figure a team can be trusted with is its spread over many draws, and the seed of its
worst case is the flight to look at again (``gcs fly --seeds N --record``). The
flights run in parallel processes (``gcs.app._seeds``, as ``gcs analyze --verify``'s).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gcs.app import (
    FlightResult,
    Scenario,
    SeedFlight,
    fly_seed,
    fly_seeds_in_parallel,
    jobs_for,
    load_scenario,
    parse_seeds,
    seeds_text,
)
from gcs.config import Team, load_team
from gcs.testing._metrics import Metrics

__all__ = ["LESS_IS_WORSE", "SeedRun", "SeedRuns", "Spread", "fly_seeds", "format_seed_runs",
           "spread"]

#: The figures whose worst case is their least (all others: their greatest).
LESS_IS_WORSE = frozenset({"payload_lift_m", "rope_tension_min_N", "real_time_factor"})


@dataclass(frozen=True)
class SeedRun:
    """One seed's flight: its figures (None if the flight never started) and, if it did
    not complete, why."""

    seed: int
    metrics: Metrics | None
    error: str | None
    wall_s: float
    record: str | None = None

    @property
    def completed(self) -> bool:
        return self.error is None

    def figures(self) -> dict[str, float]:
        """The numeric figures, by-phase ones as ``name.phase``; unmeasured left out."""
        out: dict[str, float] = {}
        for name, value in ({} if self.metrics is None else self.metrics.to_dict()).items():
            if isinstance(value, Mapping):
                out |= {f"{name}.{k}": float(v) for k, v in value.items() if v is not None}
            elif isinstance(value, int | float) and not isinstance(value, bool):
                out[name] = float(value)
        return out

    def to_json(self) -> dict[str, object]:
        """The flight as ``gcs fly --json`` prints it, with its seed and wall time."""
        figures = {} if self.metrics is None else self.metrics.to_dict()
        return {"seed": self.seed, **figures, "completed": self.completed, "error": self.error,
                "record": self.record, "wall_s": round(self.wall_s, 1)}


@dataclass(frozen=True)
class Spread:
    """One figure over the completed flights that measured it."""

    n: int
    min: float
    median: float
    p90: float
    max: float
    mean: float
    worst_seed: int
    """The seed of the worst flight: the largest figure, or the least for
    :data:`LESS_IS_WORSE`."""

    def to_json(self) -> dict[str, object]:
        return {"n": self.n, "min": _num(self.min), "median": _num(self.median),
                "p90": _num(self.p90), "max": _num(self.max), "mean": _num(self.mean),
                "worst_seed": self.worst_seed}


def spread(runs: Sequence[SeedRun]) -> dict[str, Spread]:
    """Each figure's spread over the completed ``runs`` (a figure none measured: absent)."""
    by_figure: dict[str, dict[int, float]] = {}
    for run in runs:
        if run.completed:
            for name, value in run.figures().items():
                if math.isfinite(value):
                    by_figure.setdefault(name, {})[run.seed] = value
    out = {}
    for name, values in by_figure.items():
        seeds = np.array(list(values))
        x = np.array(list(values.values()))
        worst = int(np.argmin(x) if name in LESS_IS_WORSE else np.argmax(x))
        out[name] = Spread(n=len(x), min=float(x.min()), median=float(np.median(x)),
                           p90=float(np.percentile(x, 90)), max=float(x.max()),
                           mean=float(x.mean()), worst_seed=int(seeds[worst]))
    return out


@dataclass(frozen=True)
class SeedRuns:
    """The flights of one scenario, one per seed, and the spread of their figures."""

    team: str
    scenario: str
    seeds: tuple[int, ...]
    jobs: int
    wall_s: float
    runs: tuple[SeedRun, ...]
    summary: Mapping[str, Spread]
    """:func:`spread` of ``runs``: the completed flights only."""

    @property
    def failed(self) -> tuple[SeedRun, ...]:
        return tuple(r for r in self.runs if not r.completed)

    @property
    def ok(self) -> bool:
        """Every flight completed."""
        return not self.failed

    @property
    def flights_per_minute(self) -> float:
        return 60.0 * len(self.runs) / self.wall_s if self.wall_s > 0 else math.inf

    def run(self, seed: int) -> SeedRun:
        """The flight of ``seed``."""
        return next(r for r in self.runs if r.seed == seed)

    def to_json(self) -> dict[str, object]:
        return {"team": self.team, "scenario": self.scenario, "seeds": list(self.seeds),
                "jobs": self.jobs, "wall_s": round(self.wall_s, 1),
                "flights_per_minute": _num(self.flights_per_minute),
                "completed": len(self.runs) - len(self.failed),
                "flights": [r.to_json() for r in self.runs],
                "summary": {k: s.to_json() for k, s in self.summary.items()},
                "failed": [{"seed": r.seed, "error": r.error} for r in self.failed],
                "ok": self.ok}


def _num(x: float) -> float | None:
    return round(float(x), 4) + 0.0 if math.isfinite(x) else None


def _text(x: float) -> str:
    return f"{x:.4g}" if abs(x) < 1e4 else f"{x:.0f}"


def format_seed_runs(runs: SeedRuns) -> str:
    """The table: figure | min | median | p90 | max | mean | worst seed, over the completed
    flights; then the flights that did not complete, with their reasons."""
    head = ("figure", "min", "median", "p90", "max", "mean", "worst seed")
    body = [(name, *(_text(v) for v in (s.min, s.median, s.p90, s.max, s.mean)),
             str(s.worst_seed)) for name, s in runs.summary.items()]
    widths = [max(len(row[i]) for row in (head, *body)) for i in range(len(head))]
    done = len(runs.runs) - len(runs.failed)
    lines = [f"{runs.scenario} on {runs.team}: {len(runs.runs)} flight(s), seeds "
             f"{seeds_text(runs.seeds)}, {runs.jobs} at a time, {runs.wall_s:.0f} s "
             f"({runs.flights_per_minute:.1f} flights/min); {done} of {len(runs.runs)} "
             f"completed"]
    if body:
        lines += ["  " + "  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True))
                  .rstrip() for row in (head, *body)]
    lines += [f"FLIGHT seed {r.seed} did not complete: {r.error}" for r in runs.failed]
    return "\n".join(lines)


def _seed_run(flight: SeedFlight) -> SeedRun:
    result = flight.result
    metrics = Metrics.from_json(result.metrics) if result.metrics else None  # None: lost
    return SeedRun(seed=flight.seed, metrics=metrics, error=result.error,
                   wall_s=flight.wall_s, record=result.record)


def _lost(seed: int, why: str) -> SeedFlight:
    return SeedFlight(seed=seed, result=FlightResult(metrics={}, error=why, record=None),
                      wall_s=0.0)


def fly_seeds(config: str | Path | Team, scenario: str | Path | Scenario,
              seeds: Sequence[int] | str, *, jobs: int | None = None, speed: str = "max",
              record: str | Path | None = None, insecure: bool = False,
              override_analysis: bool = False,
              progress: Callable[[str], None] | None = None,
              gusts: float | None = None) -> SeedRuns:
    """Fly ``scenario`` once per seed of the simulator (``"1-20"`` or a list), each in
    lockstep in a process of its own, ``jobs`` at a time (default: the machine's cores).

    ``record``: each flight to a .tlog named after it and its seed
    (``runs/f.tlog`` gives ``runs/f_seed3.tlog``); ``gusts``: the simulator's
    turbulence, m/s per axis (None: calm); ``progress`` gets a line as the
    flights start and one per flight that ends. A flight that did not complete is in
    :attr:`SeedRuns.failed` with its reason; the summary is of the completed ones.
    """
    team = config if isinstance(config, Team) else load_team(config)
    if insecure:
        team = team.without_signing()
    plan = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    seeds = parse_seeds(seeds) if isinstance(seeds, str) else tuple(seeds)
    if not seeds:
        raise ValueError("fly_seeds: no seeds to fly")
    jobs = jobs_for(jobs, len(seeds))
    work = functools.partial(fly_seed, team, plan, speed=speed,
                             record=None if record is None else str(record),
                             override_analysis=override_analysis, gusts=gusts)
    wall0 = time.monotonic()
    flights = fly_seeds_in_parallel(team, work, seeds, jobs=jobs, lost=_lost, say=progress,
                                    error_of=lambda f: f.result.error)
    runs = tuple(_seed_run(f) for f in flights)
    return SeedRuns(team=team.config.name, scenario=plan.name, seeds=seeds, jobs=jobs,
                    wall_s=time.monotonic() - wall0, runs=runs, summary=spread(runs))
