"""Monte-Carlo flights: flights a minute of ``gcs fly --seeds``, one job against several.

Flies the same K seeds (default 1-20) of a scenario (default: the paper's flight on
the paper's square) with ``gcs fly --seeds 1-K --jobs J --json --quiet``, once per
value of ``--jobs`` (default 1 then 2), each a fresh command as a user runs it, and
prints a line per run, then one JSON object on the last line:

    {"seeds": 20, "runs": [{"jobs": 1, "wall_s": ..., "flights_per_minute": ...,
     "completed": 20, "load_avg_1min": [before, after], ...}, ...], "speedup": {"2": 1.9}}

``wall_s`` is the whole command (start-up included); ``cores_busy`` its CPU time
(every process it started) over that; ``speedup`` is each run's flights a minute
over the first run's. In lockstep a flight's simulator and GCS mostly take turns
(the paper's flight alone keeps one core busy and part of another:
docs/performance.md), so the speed-up is bounded by the free cores over that. Exit
status 1 unless every flight completed.

    python bench/monte_carlo.py [--seeds 20] [--jobs 1,2] [--config C] [--scenario S]
                                [--override-analysis]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]


def fly_seeds(config: str, scenario: str, seeds: int, jobs: int,
              override: bool) -> dict[str, Any]:
    """One ``gcs fly --seeds 1-K --jobs J`` command: its wall time and its JSON."""
    argv = [sys.executable, "-m", "gcs", "fly", "--config", config, "--scenario", scenario,
            "--seeds", f"1-{seeds}" if seeds > 1 else "1", "--jobs", str(jobs), "--json",
            "--quiet", *(["--override-analysis"] if override else [])]
    load0 = os.getloadavg()[0]
    cpu0 = _children_cpu()
    wall0 = time.monotonic()
    out = subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, check=False)
    wall = time.monotonic() - wall0
    cpu = _children_cpu() - cpu0
    try:
        data = json.loads(out.stdout.splitlines()[-1])
    except (IndexError, json.JSONDecodeError):
        sys.exit(f"monte_carlo: gcs fly --jobs {jobs} gave no JSON (exit {out.returncode}): "
                 f"{out.stderr.strip()[-500:]}")
    return {"jobs": jobs, "wall_s": round(wall, 1), "pool_wall_s": data["wall_s"],
            "flights_per_minute": round(60.0 * seeds / wall, 2),
            "completed": data["completed"],
            "failed": data["failed"],
            "flight_wall_s_median": _median([f["wall_s"] for f in data["flights"]]),
            "cpu_s_per_flight": round(cpu / seeds, 1), "cores_busy": round(cpu / wall, 2),
            "worst_distance_error_m_max": data["summary"].get("worst_distance_error_m",
                                                              {}).get("max"),
            "load_avg_1min": [round(load0, 2), round(os.getloadavg()[0], 2)]}


def _children_cpu() -> float:
    """CPU seconds (user and system) of every process this one started and waited for:
    the command, its workers and their simulators."""
    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    return use.ru_utime + use.ru_stime


def _median(values: list[float]) -> float | None:
    ordered = sorted(values)
    return ordered[len(ordered) // 2] if ordered else None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="seeds 1..K flown (default 20)")
    parser.add_argument("--jobs", default="1,2",
                        help="values of --jobs, one command each (default 1,2)")
    parser.add_argument("--config", default="configs/bebop_square.yaml", help="team config")
    parser.add_argument("--scenario", default="configs/scenarios/paper_flight.yaml",
                        help="scenario flown (default: the paper's flight)")
    parser.add_argument("--override-analysis", action="store_true",
                        help="fly a team that gcs analyze refuses")
    args = parser.parse_args()
    if args.seeds < 1:
        parser.error("--seeds: at least 1")
    try:
        jobs = [int(j) for j in args.jobs.split(",")]
    except ValueError:
        parser.error(f"--jobs: expected numbers such as 1,2, got {args.jobs!r}")
    runs = []
    for j in jobs:
        run = fly_seeds(args.config, args.scenario, args.seeds, j, args.override_analysis)
        runs.append(run)
        print(f"{args.seeds} flights, {j} at a time: {run['wall_s']} s, "
              f"{run['flights_per_minute']} flights/min, {run['completed']} completed "
              f"(a flight {run['flight_wall_s_median']} s, {run['cpu_s_per_flight']} CPU s; "
              f"{run['cores_busy']} cores busy; load {run['load_avg_1min']})",
              flush=True)
    base = runs[0]["flights_per_minute"]
    speedup = {str(r["jobs"]): round(r["flights_per_minute"] / base, 2) for r in runs[1:]}
    print(json.dumps({"seeds": args.seeds, "config": args.config, "scenario": args.scenario,
                      "cpus": os.cpu_count(), "runs": runs, "speedup": speedup}))
    sys.exit(0 if all(r["completed"] == args.seeds for r in runs) else 1)


if __name__ == "__main__":
    main()
