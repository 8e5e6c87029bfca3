"""Flights of many seeds in parallel: one lockstep flight per simulator seed, N at a time.

Why: a lockstep flight is the flight of one seed of the simulator's sensor noise and
gusts, the same on every run; what a team does in general is the spread over seeds
(``gcs fly --seeds``, :func:`gcs.testing.fly_seeds`) and what it does at worst is held
to the analysis (``gcs analyze --verify``). Both fly here: each flight in a worker
process of its own (a fresh interpreter: no zenoh session or thread inherited), with
its simulator beside it, ``jobs`` at a time. In lockstep the simulator and the GCS of a
flight mostly take turns, so a flight keeps one core busy and part of another and
flights in parallel take the others (figures: docs/performance.md,
``bench/monte_carlo.py``). A worker that raises or dies gives a flight that did not
complete, with the reason: no seed is ever lost.
"""

from __future__ import annotations

import contextlib
import io
import math
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TypeVar

from gcs.app._fly import FlightResult, fly
from gcs.app._scenario import Scenario
from gcs.common import ConfigError
from gcs.config import Team, signing_line

__all__ = ["SeedFlight", "fly_seed", "fly_seeds_in_parallel", "jobs_for", "parse_gusts",
           "parse_jobs",
           "parse_seeds", "seed_record", "seeds_text"]

R = TypeVar("R")


def parse_seeds(text: str) -> tuple[int, ...]:
    """``"1-4"``, ``"7"`` or ``"1,3,9-10"`` as the seeds, in order, each once."""
    seeds: list[int] = []
    try:
        for part in text.split(","):
            lo, _, hi = part.strip().partition("-")
            first, last = int(lo), int(hi) if hi else int(lo)
            if first < 0 or last < first or last - first > 9999:
                raise ValueError
            seeds += [s for s in range(first, last + 1) if s not in seeds]
    except ValueError:
        raise ConfigError("--seeds", "", f"expected seeds such as 1-4 or 1,3,7 "
                          f"(non-negative, ranges low-high), got {text!r}") from None
    return tuple(seeds)


def parse_jobs(text: str | int | None) -> int | None:
    """``--jobs``: flights at a time, at least 1 (None: the machine's cores)."""
    if text is None:
        return None
    try:
        jobs = int(text)
    except ValueError:
        jobs = 0
    if jobs < 1:
        raise ConfigError("--jobs", "", f"expected the number of flights at a time, at "
                          f"least 1, got {str(text)!r}")
    return jobs


def parse_gusts(text: str | float | None) -> float | None:
    """``--gusts``: the simulator's turbulence, m/s per axis, 0 or more (None: calm)."""
    if text is None:
        return None
    try:
        gusts = float(text)
    except ValueError:
        gusts = math.nan
    if not (math.isfinite(gusts) and gusts >= 0.0):
        raise ConfigError("--gusts", "", f"expected the gusts' standard deviation per axis, "
                          f"0 or more m/s (e.g. 0.5), got {str(text)!r}")
    return gusts


def seeds_text(seeds: Sequence[int]) -> str:
    """The seeds as ``--seeds`` takes them: ``1-4`` for a run of them, else ``1,3,7``."""
    seeds = tuple(seeds)
    if len(seeds) > 1 and seeds == tuple(range(seeds[0], seeds[-1] + 1)):
        return f"{seeds[0]}-{seeds[-1]}"
    return ",".join(str(s) for s in seeds)


def seed_record(record: str | Path, seed: int) -> Path:
    """Where the flight of ``seed`` is recorded when ``record`` names them all:
    ``runs/flight.tlog`` gives ``runs/flight_seed3.tlog``."""
    path = Path(record)
    return path.with_name(f"{path.stem}_seed{seed}{path.suffix or '.tlog'}")


class _Prefixed(io.TextIOBase):
    """A text stream that writes whole lines to ``out``, each after ``prefix``."""

    def __init__(self, out: IO[str], prefix: str) -> None:
        super().__init__()
        self._out, self._prefix, self._buf = out, prefix, ""

    def write(self, text: str) -> int:
        self._buf += text
        *lines, self._buf = self._buf.split("\n")
        for line in lines:
            self._out.write(f"{self._prefix}{line}\n")
        self._out.flush()
        return len(text)

    def flush(self) -> None:
        self._out.flush()


@dataclass(frozen=True)
class SeedFlight:
    """One seed's flight, as a worker flew it."""

    seed: int
    result: FlightResult
    wall_s: float
    """Wall time of the whole flight, simulator start and stop included, s."""


def fly_seed(team: Team, scenario: Scenario, seed: int, *, speed: str = "max",
             record: str | None = None, progress: bool = False,
             override_analysis: bool = False, gusts: float | None = None) -> SeedFlight:
    """In a worker process: fly ``scenario`` with the simulator's ``seed``, recorded to
    :func:`seed_record` of ``record`` if given; with ``progress``, the flight's lines go
    to stderr, each prefixed with the seed."""
    wall0 = time.monotonic()
    path = None if record is None else seed_record(record, seed)
    with contextlib.redirect_stderr(_Prefixed(sys.stderr, f"  seed {seed}: ")):
        result = fly(team, scenario, speed=speed, record=path, progress=progress, seed=seed,
                     override_analysis=override_analysis, gusts=gusts)
    return SeedFlight(seed=seed, result=result, wall_s=time.monotonic() - wall0)


def fly_seeds_in_parallel(team: Team, work: Callable[[int], R], seeds: Sequence[int], *,
                          jobs: int, lost: Callable[[int, str], R],
                          error_of: Callable[[R], str | None],
                          say: Callable[[str], None] | None = None) -> list[R]:
    """``work(seed)`` for every seed in worker processes, ``jobs`` at a time; the
    results in the order of ``seeds``.

    ``work`` flies ``team`` (picklable: a module-level function or a
    ``functools.partial`` of one, e.g. of :func:`fly_seed`). A worker that raised or
    died gives ``lost(seed, reason)``. ``say`` gets a line as the flights start and one
    per finished flight, with ``error_of`` its result (None: it completed).
    """
    tell = say or (lambda _line: None)
    tell(signing_line(team.config.gcs, Path(team.source).parent))  # the key, before any sim
    wall0 = time.monotonic()
    done: dict[int, R] = {}
    with ProcessPoolExecutor(max_workers=jobs,
                             mp_context=multiprocessing.get_context("spawn")) as pool:
        futures: dict[Future[R], int] = {pool.submit(work, seed): seed for seed in seeds}
        tell(f"flying {len(seeds)} flight(s), seeds {seeds_text(seeds)}, {jobs} at a time")
        for future in as_completed(futures):
            seed = futures[future]
            try:
                result = future.result()
            except Exception as exc:  # the flight raised, or the worker died
                result = lost(seed, f"{type(exc).__name__}: {exc}")
            done[seed] = result
            error = error_of(result)
            state = "completed" if error is None else f"did NOT complete: {error}"
            tell(f"seed {seed} {state} ({len(done)}/{len(seeds)}, "
                 f"{time.monotonic() - wall0:.0f} s)")
    return [done[seed] for seed in seeds]


def jobs_for(jobs: int | None, flights: int) -> int:
    """Flights at a time: ``jobs``, or the machine's cores, never more than the flights."""
    return max(1, min(jobs or os.cpu_count() or 1, flights))
