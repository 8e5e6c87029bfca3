"""``gcs analyze --verify``: fly the team in the simulator and hold the analysis to it.

Why: the analysis is a certificate an operator trusts before lifting a payload with
real vehicles; flights in the lockstep simulator, one per seed of its sensor noise
and gusts, check that no vehicle carried more, pulled harder, tilted further or
strayed further from its shape than the analysis says it can. Each flight is a
:func:`gcs.app.fly` in a process of its own (they run in parallel, as every flight of
many seeds: ``_seeds``), recorded to a temporary .tlog and measured from the
simulator's truth in it, at the guidance ticks: the rope tensions, the vehicles' and
the payload's true positions.

The figures, each a bound the measured worst over every flight must stay under
(:data:`FIGURES`; :func:`compare` is the plain comparison):

* a vehicle's vertical load share (the vertical part of its rope's pull over the
  payload's weight, while the payload is up) against the design share, or the share
  with the payload accelerating at ``limits.accel_norm`` where that is larger, and
  against the worst share within ``analysis.position_error``;
* the rope tension against the tension of a rope carrying the design share at the
  rope angle at rest (or the largest tension accelerating, where larger), and against
  the worst tension of the analysis;
* the horizontal rope pull (eq. Th) against what leaves ``limits.accel_norm`` at
  the bank limit (``F_h - m a``, the pull at the safe span);
* the tilt (from every ATTITUDE while airborne) against the bank limit;
* the span (twice a vehicle's horizontal distance to the payload, eq. Th's
  ``||z2||``) against the safe span;
* the worst distance error of the flown phases (as ``gcs fly`` reports it) against
  the safe deformation and against eq. max's ``analysis.max_distance_error``.
"""

from __future__ import annotations

import functools
import math
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gcs.analysis import Analysis, accelerating_share, safe_guidance
from gcs.app._scenario import Scenario, load_scenario, scenario_scales
from gcs.app._seeds import fly_seed, fly_seeds_in_parallel, jobs_for, seed_record, seeds_text
from gcs.config import Team
from gcs.flightlog import FlightLog, tilt_angle
from gcs.loop import Phase

__all__ = ["FIGURES", "Figure", "FlightFigures", "Row", "VerifyResult", "compare",
           "format_verify", "measure_flight", "predictions", "rope_loads", "verify"]

_LIFTED = 0.05
"""The payload counts as carried above this height, m (as the flight metrics count it)."""


@dataclass(frozen=True)
class Figure:
    """One line of the verification: a measured worst case held to a predicted bound."""

    key: str
    """Name of the prediction (see :func:`predictions`) and of the row in ``--json``."""
    label: str
    measured: str
    """Name of the flight's measurement (a field of :class:`FlightFigures`)."""
    unit: str


#: The rows of the table, in order.
FIGURES = (
    Figure("share_design", "vertical load share <= design share (or accelerating, at the "
           "scales flown)", "share", ""),
    Figure("share_worst", "vertical load share <= worst share within position_error",
           "share", ""),
    Figure("tension_design", "rope tension <= tension at the design share (or accelerating, "
           "at the scales flown)", "tension", "N"),
    Figure("tension_worst", "rope tension <= worst tension", "tension", "N"),
    Figure("pull_safe", "horizontal rope pull <= eq. Th at the safe span", "pull", "N"),
    Figure("tilt_bank", "tilt <= bank limit", "tilt", "rad"),
    Figure("span_safe", "span (2 x reach to the payload) <= safe span", "span", "m"),
    Figure("error_safe", "distance error <= safe deformation", "distance_error", "m"),
    Figure("error_eq_max", "distance error <= eq. max's max_distance_error",
           "distance_error", "m"),
)


def predictions(analysis: Analysis, team: Team,
                scales: tuple[float, ...] | None = None) -> dict[str, float]:
    """The analysis' bound behind each figure (:data:`FIGURES`' keys), SI units.

    The accelerating share and tension are taken at ``scales``, those a scenario flies
    (None: every scale the GCS flies, the certificate's): the paper flight's 0.9 to 1.1
    hold the square to 0.41 of the payload, not the 0.63 of its smallest scale flown, so
    a model that is wrong where the flight went still shows.
    """
    cfg = team.config
    ld = analysis.load
    weight = cfg.payload.mass * analysis.gravity
    accel_share, accel_tension = ld.accel_share, ld.accel_tension
    if scales is not None and math.isfinite(accel_share):
        flown = accelerating_share(team, cfg.limits.accel_norm, scales)
        accel_share, accel_tension = flown.share, flown.tension
    return {
        "share_design": max(ld.design_share, accel_share),
        "share_worst": ld.worst_share,
        "tension_design": max(ld.design_share * weight / math.cos(analysis.equilibrium_rope_angle),
                              accel_tension),
        "tension_worst": ld.worst_tension,
        "pull_safe": analysis.horizontal_force - cfg.airframe.mass * cfg.limits.accel_norm,
        "tilt_bank": analysis.bank_limit,
        "span_safe": analysis.safe_span,
        "error_safe": analysis.safe_deformation,
        "error_eq_max": cfg.analysis.max_distance_error,
    }


@dataclass(frozen=True)
class FlightFigures:
    """The worst cases of one flight (None: not measured, e.g. the payload never rose)."""

    seed: int
    completed: bool
    error: str | None
    wall_s: float
    share: float | None = None
    tension: float | None = None
    pull: float | None = None
    tilt: float | None = None
    span: float | None = None
    distance_error: float | None = None
    payload_lift: float | None = None

    def value(self, name: str) -> float | None:
        v = getattr(self, name)
        return None if v is None else float(v)


def rope_loads(payload_ned: np.ndarray, vehicles_ned: np.ndarray,
               tension: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each rope's pull on its vehicle from samples of the truth: ``payload_ned`` (K, 3),
    ``vehicles_ned`` (K, n, 3), ``tension`` (K, n) N.

    Returns (vertical pull, horizontal pull, horizontal reach from vehicle to payload),
    each (K, n): N, N, m. The rope runs from the vehicle's centre of mass to the payload.
    """
    to_payload = payload_ned[:, None, :] - vehicles_ned
    length = np.maximum(np.linalg.norm(to_payload, axis=2), 1e-9)
    reach = np.hypot(to_payload[..., 0], to_payload[..., 1])
    return tension * to_payload[..., 2] / length, tension * reach / length, reach


def measure_flight(log: FlightLog, weight: float, *, seed: int = 0, completed: bool = True,
                   error: str | None = None, wall_s: float = 0.0) -> FlightFigures:
    """The worst cases of a recorded simulated flight; ``weight`` the payload's, N."""
    metrics = log.metrics()
    worst_error = metrics.worst_distance_error if metrics.ticks else None
    share = tension = pull = span = lift = None
    if all(k in log.arrays for k in ("payload", "rope_T", "veh_true")):
        payload = log.arrays["payload"][:, :3]
        vehicles = log.per_vehicle("veh_true", 3)
        ropes = log.per_vehicle("rope_T", 1)[..., 0]
        whole = (np.isfinite(payload).all(axis=1) & np.isfinite(vehicles).all(axis=(1, 2))
                 & np.isfinite(ropes).all(axis=1))
        if whole.any():
            lift = float(-payload[whole, 2].min())
        up = whole & (-payload[:, 2] > _LIFTED)
        if up.any():
            vertical, horizontal, reach = rope_loads(payload[up], vehicles[up], ropes[up])
            share = float(vertical.max()) / weight
            tension = float(ropes[up].max())
            pull = float(horizontal.max())
            span = 2.0 * float(reach.max())
    return FlightFigures(seed=seed, completed=completed, error=error, wall_s=wall_s,
                         share=share, tension=tension, pull=pull, tilt=_worst_tilt(log),
                         span=span, distance_error=worst_error, payload_lift=lift)


def _worst_tilt(log: FlightLog) -> float | None:
    """The largest tilt of any vehicle's ATTITUDE while the team is airborne, rad."""
    if not len(log.tick_t):
        return None
    airborne = np.array([Phase(int(p)).airborne for p in log.phase])
    worst = None
    for track in log.tracks.values():
        k = np.searchsorted(log.tick_t, track.att_t, side="right") - 1
        up = (k >= 0) & airborne[np.maximum(k, 0)]
        if up.any():
            t = float(np.nanmax(tilt_angle(track.rpy[up])))
            worst = t if worst is None else max(worst, t)
    return worst


@dataclass(frozen=True)
class Row:
    """A figure's predicted bound against its worst measurement over the flights."""

    figure: Figure
    predicted: float
    measured: float | None
    seed: int | None
    """The seed of the flight that measured it."""

    @property
    def margin(self) -> float | None:
        """How far under its bound the worst flight stayed (negative: over it)."""
        return None if self.measured is None else self.predicted - self.measured

    @property
    def ok(self) -> bool:
        """Measured, and within the bound (an unmeasured figure verifies nothing)."""
        return self.measured is not None and self.measured <= self.predicted

    def to_json(self) -> dict[str, object]:
        return {"figure": self.figure.key, "label": self.figure.label, "unit": self.figure.unit,
                "predicted": _num(self.predicted), "measured": _num(self.measured),
                "margin": _num(self.margin), "seed": self.seed, "ok": self.ok}


def compare(predicted: Mapping[str, float], flights: Sequence[FlightFigures]) -> list[Row]:
    """One row per figure: the worst measurement over ``flights`` against its bound."""
    rows = []
    for fig in FIGURES:
        worst: tuple[float, int] | None = None
        for f in flights:
            v = f.value(fig.measured)
            if v is not None and (worst is None or v > worst[0]):
                worst = (v, f.seed)
        rows.append(Row(fig, predicted[fig.key], None if worst is None else worst[0],
                        None if worst is None else worst[1]))
    return rows


@dataclass(frozen=True)
class VerifyResult:
    """The flights of a verification and their comparison with the analysis."""

    team: str
    scenario: str
    seeds: tuple[int, ...]
    jobs: int
    wall_s: float
    flights: tuple[FlightFigures, ...]
    rows: tuple[Row, ...]
    gusts: float = 0.0
    """The simulator's turbulence, m/s per axis (0: calm)."""

    @property
    def failed_flights(self) -> tuple[FlightFigures, ...]:
        return tuple(f for f in self.flights if not f.completed)

    @property
    def exceeded(self) -> tuple[Row, ...]:
        return tuple(r for r in self.rows if not r.ok)

    @property
    def ok(self) -> bool:
        """Every flight completed and stayed within every bound of the analysis."""
        return not self.failed_flights and not self.exceeded

    def to_json(self) -> dict[str, object]:
        return {
            "team": self.team, "scenario": self.scenario, "seeds": list(self.seeds),
            "jobs": self.jobs, "wall_s": round(self.wall_s, 1),
            "gusts_m_s": _num(self.gusts),
            "figures": [r.to_json() for r in self.rows],
            "flights": [{"seed": f.seed, "completed": f.completed, "error": f.error,
                         "wall_s": round(f.wall_s, 1), "share": _num(f.share),
                         "tension_N": _num(f.tension), "pull_N": _num(f.pull),
                         "tilt_rad": _num(f.tilt), "span_m": _num(f.span),
                         "distance_error_m": _num(f.distance_error),
                         "payload_lift_m": _num(f.payload_lift)} for f in self.flights],
            "exceeded": [r.figure.key for r in self.exceeded],
            "ok": self.ok,
        }


def _num(x: float | None) -> float | None:
    return None if x is None or not math.isfinite(x) else round(float(x), 4) + 0.0


def format_verify(result: VerifyResult) -> str:
    """The table: figure | predicted | measured (worst over the seeds) | margin | verdict."""
    head = ("figure", "predicted", "measured (seed)", "margin", "")
    body = []
    for r in result.rows:
        unit = f" {r.figure.unit}" if r.figure.unit else ""
        measured = ("not measured" if r.measured is None
                    else f"{r.measured:.3f}{unit} ({r.seed})")
        margin = "" if r.margin is None else f"{r.margin:+.3f}{unit}"
        body.append((r.figure.label, f"{r.predicted:.3f}{unit}", measured, margin,
                     "OK" if r.ok else "EXCEEDED"))
    widths = [max(len(row[i]) for row in (head, *body)) for i in range(len(head))]
    lines = [f"verification of {result.team} in the simulator: {result.scenario}, "
             f"seeds {seeds_text(result.seeds)}, "
             f"{f'gusts {result.gusts:g} m/s per axis' if result.gusts else 'calm'}, "
             f"{result.jobs} at a time, {result.wall_s:.0f} s"]
    lines += ["  " + "  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
              for row in (head, *body)]
    lines += [f"FLIGHT seed {f.seed} did not complete: {f.error}" for f in result.failed_flights]
    lines += [f"EXCEEDED {r.figure.key}: measured {r.measured:.3f} (seed {r.seed}) > "
              f"predicted {r.predicted:.3f}" if r.measured is not None else
              f"EXCEEDED {r.figure.key}: not measured (the payload never rose "
              f"{_LIFTED:g} m, or nothing was recorded)" for r in result.exceeded]
    if result.ok:
        lines.append(f"result: OK ({len(result.flights)} flights within the analysis)")
    else:
        lines.append(f"result: FAILED ({len(result.exceeded)} figure(s) exceeded, "
                     f"{len(result.failed_flights)} flight(s) incomplete)")
    return "\n".join(lines)


def _fly_and_measure(team: Team, scenario: Scenario, record: str, progress: bool,
                     gusts: float | None, unchecked: bool, seed: int) -> FlightFigures:
    """In a worker process: fly one seed, recorded, and measure it (``unchecked``: a team
    the analysis refuses for its size only, whose flights are its certificate)."""
    flight = fly_seed(team, scenario, seed, record=record, progress=progress, gusts=gusts,
                      override_analysis=unchecked)
    result = flight.result
    weight = team.config.payload.mass * team.config.analysis.gravity
    try:
        log = FlightLog.load(seed_record(record, seed))
    except Exception as exc:  # nothing recorded: the flight did not get far
        return FlightFigures(seed=seed, completed=False, wall_s=flight.wall_s,
                             error=result.error or f"no log: {exc}")
    return measure_flight(log, weight, seed=seed, completed=result.error is None,
                          error=result.error, wall_s=flight.wall_s)


def verify(team: Team, scenario: str | Path, analysis: Analysis, *,
           seeds: Sequence[int] = (1, 2, 3, 4), jobs: int | None = None,
           progress: Callable[[str], None] | None = None,
           flight_progress: bool = True, gusts: float | None = None) -> VerifyResult:
    """Fly ``scenario`` once per seed, ``jobs`` flights at a time (default: the machine's
    cores), and compare the worst of each figure with ``analysis``. ``gusts``: the
    simulator's turbulence, m/s per axis (None: its world's, calm).

    ``progress`` gets one line per flight started and ended; ``flight_progress``
    lets each flight print its steps on stderr, prefixed with its seed.
    """
    jobs = jobs_for(jobs, len(seeds))
    wall0 = time.monotonic()
    script = load_scenario(scenario)
    scales = scenario_scales(script, safe_guidance(team, analysis))
    with tempfile.TemporaryDirectory(prefix="gcs-verify-") as tmp:
        work = functools.partial(_fly_and_measure, team, script,
                                 str(Path(tmp) / "flight.tlog"), flight_progress, gusts,
                                 analysis.unchecked_only)
        flights = fly_seeds_in_parallel(
            team, work, seeds, jobs=jobs, say=progress, error_of=lambda f: f.error,
            lost=lambda seed, why: FlightFigures(seed=seed, completed=False, wall_s=0.0,
                                                 error=why))
    name = Path(scenario).stem
    return VerifyResult(team=team.config.name, scenario=name, seeds=tuple(seeds), jobs=jobs,
                        wall_s=time.monotonic() - wall0, flights=tuple(flights),
                        rows=tuple(compare(predictions(analysis, team, scales), flights)),
                        gusts=gusts or 0.0)
