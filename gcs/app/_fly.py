"""``gcs fly``: a headless flight of a scenario with simulated vehicles, and its metrics.

Starts the simulated team behind zenoh (or joins a running ``gcs sim``), plays
the scenario through the same operator command and phase actions as the
browser, and returns the flight metrics. With the sim started here the GCS and
the sim run in lockstep, so the flight is as fast as the machine allows (or
paced with ``speed``) and repeatable.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

from gcs.app._app import GcsApp
from gcs.app._scenario import Scenario, ScenarioError, Step, play
from gcs.app._simprocess import SimProcess, free_tcp_port
from gcs.config import Team
from gcs.flightlog import FlightMetrics
from gcs.loop import GatedClock
from gcs.transport import ZenohSettings

__all__ = ["FlightResult", "fly"]


@dataclass
class FlightResult:
    """Metrics of a flight and, if it did not complete, why."""

    metrics: dict[str, object]
    error: str | None
    record: str | None

    def to_json(self) -> dict[str, object]:
        return {**self.metrics, "completed": self.error is None, "error": self.error,
                "record": self.record}


def fly(team: Team, scenario: Scenario, *, speed: str = "max", record: Path | None = None,
        connect: str | None = None, progress: bool = True) -> FlightResult:
    """Fly ``scenario``; blocks until it ends. ``connect``: endpoint of a running sim."""
    sim: SimProcess | None = None
    if connect is None:
        endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
        sim = SimProcess(team.source, endpoint=endpoint, speed=speed, lockstep=True)
    else:
        endpoint = connect
    settings = ZenohSettings(mode="peer", connect=(endpoint,))
    metrics = FlightMetrics()
    error: str | None = None
    loop: dict[str, object] = {}
    wall0 = time.monotonic()
    try:
        with GcsApp(team, zenoh_settings=settings, sim_clock=True, lockstep=sim is not None,
                    record=record) as app:
            app.add_listener(lambda snap, _truth: metrics.add(snap))

            def show(k: int, step: Step) -> None:
                if progress:
                    print(f"[t={app.clock.now():7.2f} s] step {k + 1}/{len(scenario.steps)}: "
                          f"{step.describe()}", file=sys.stderr, flush=True)

            # In lockstep the scenario acts at ticks only, so every run is the same flight.
            with app.gate.participant():
                app.start()
                try:
                    play(scenario, app.loop, GatedClock(app.clock, app.gate), on_step=show)
                except ScenarioError as exc:
                    error = str(exc)
                except Exception as exc:  # the clock stopped, the sim died...
                    error = f"{type(exc).__name__}: {exc}"
            stats = app.loop.stats()
            loop = {"loop_stall_max_s": round(stats.stall_max, 3),
                    "setpoint_gap_max_s": round(stats.setpoint_gap_max, 3),
                    "recoveries": app.loop.recovery.attempts}
            if sim is not None and not sim.alive():
                error = (error or "") + " (simulator exited: " + " | ".join(
                    sim.stderr_tail[-3:]) + ")"
    finally:
        if sim is not None:
            sim.close()
    wall = time.monotonic() - wall0
    return FlightResult(metrics=metrics.to_json(wall_seconds=wall) | loop, error=error,
                        record=str(record) if record is not None else None)
