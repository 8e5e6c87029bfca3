"""How fast the simulated team runs: real-time factors of physics plus autopilots.

Runs 4 Bebops with the paper's payload, then rings of 16 and 64 vehicles, each
flying OFFBOARD for a fixed simulated time with x/y acceleration setpoints
refreshed at the GCS's 4 Hz (so Python's per-chunk overhead is included).
Autopilots run at 512 Hz, physics at the configured rate (2048 Hz by
default). The JIT compile (or cache load) and the take-off happen before the
clock starts: the factors measure steady running only. The process is pinned
to one CPU core where the OS allows it; numba runs single-threaded anyway.

Prints one line per team, then one JSON object on the last line, also when a
team fails (refused or left OFFBOARD, take-off not done): then its factor is
null, "error" says what happened, and the exit status is 1.

    python bench/sim_speed.py [--seconds 10]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections import Counter

import numpy as np

from gcs.wire import SimMode
from sim import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    Layout,
    build_team,
    load_world_config,
    paper_square,
    ring_layout,
    take_off,
)
from vehicles import load_airframe, load_autopilot_config

TARGETS = {"4+payload": 100.0, "16": None, "64": 5.0}
"""Required real-time factors (None: reported only)."""


class BenchError(RuntimeError):
    """A team did not fly OFFBOARD throughout, so its factor would time something else."""


def measure(layout: Layout, sim_seconds: float, seed: int) -> tuple[float, float]:
    """(real-time factor, seconds spent before timing) for one team."""
    started = time.perf_counter()
    world, autopilot = build_team(layout, payload_mass=0.4, rng=np.random.default_rng(seed),
                                  airframe=load_airframe(DEFAULT_AIRFRAME),
                                  world_config=load_world_config(DEFAULT_WORLD_CONFIG),
                                  autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    take_off(world, autopilot, 1.5)  # compiles (or loads the cache) and lifts the payload
    z_hold = autopilot.state.p_hold[:, 2].copy()
    n = world.n_vehicles

    def send(t: float) -> None:
        accel = 0.3 * np.array([math.cos(0.5 * t), math.sin(0.5 * t)])
        for i in range(n):
            autopilot.set_accel_xy_pos_z_setpoint(i, accel, z_hold[i])

    send(0.0)
    refused = [str(i) for i in range(n) if not autopilot.start_offboard(i).accepted]
    if refused:
        raise BenchError(f"vehicles {', '.join(refused)} refused OFFBOARD")
    chunk = 0.25
    setup = time.perf_counter() - started
    wall = time.perf_counter()
    for k in range(round(sim_seconds / chunk)):
        world.run(autopilot, chunk)
        send((k + 1) * chunk)
    wall = time.perf_counter() - wall
    left = [(i, m.name) for i, m in enumerate(autopilot.modes) if m != SimMode.OFFBOARD]
    if left:
        modes = Counter(mode for _, mode in left)
        now_in = ", ".join(f"{count} in {mode}" for mode, count in modes.items())
        raise BenchError(f"{len(left)} of {n} vehicles left OFFBOARD during the benchmark "
                         f"({now_in}; first: vehicle {left[0][0]})")
    return sim_seconds / wall, setup


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0, help="simulated seconds per team")
    args = parser.parse_args()
    pinned = False
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
        pinned = True
    teams = {"4+payload": paper_square(), "16": ring_layout(16), "64": ring_layout(64)}
    factors: dict[str, float | None] = {}
    setups: dict[str, float] = {}
    errors = []
    for seed, (name, layout) in enumerate(teams.items()):
        try:
            factor, setups[name] = measure(layout, args.seconds, seed)
        except RuntimeError as error:  # BenchError, or take_off's refusal or timeout
            factors[name] = None
            errors.append(f"{name}: {error}")
            print(f"{name:>10}: FAILED, {error}")
            continue
        factors[name] = factor
        target = TARGETS[name]
        verdict = "" if target is None else (" ok" if factor >= target
                                             else f" BELOW TARGET {target:g}x")
        print(f"{name:>10}: {factor:7.1f}x real time "
              f"(setup incl. JIT {setups[name]:.1f} s, not timed){verdict}")
    print(json.dumps({
        "real_time_factor": {k: None if v is None else round(v, 1)
                             for k, v in factors.items()},
        "targets": {k: v for k, v in TARGETS.items() if v is not None},
        "sim_seconds": args.seconds,
        "control_rate_hz": load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG).rate_hz,
        "physics_rate_hz": load_world_config(DEFAULT_WORLD_CONFIG).physics_rate_hz,
        "jit_compile_excluded": True,
        "setup_seconds_incl_jit": {k: round(v, 2) for k, v in setups.items()},
        "pinned_to_one_core": pinned,
        "error": "; ".join(errors) or None,
    }))
    if errors:
        sys.exit(1)


if __name__ == "__main__":
    main()
