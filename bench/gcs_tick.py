"""Cost of one GCS tick (telemetry in, guidance, setpoints out) for 4 and 100 vehicles.

A real GCS process part (GcsApp: links over a real zenoh session, runtime,
guidance, MAVLink encoding) runs on the wall clock at the team's guidance rate
while this script plays the vehicles: each publishes HEARTBEAT,
LOCAL_POSITION_NED and ATTITUDE at 20 Hz on its zenoh key, so every tick reads
fresh telemetry of every vehicle and sends every vehicle a setpoint. The
runtime is put in formation flight directly (the phase machine is not what is
measured). With ``--vehicles-in-background`` the vehicles' process publishes
as a sim host started with ``--background`` steps (in the background while on
schedule, :mod:`sim._priority`). Prints one JSON object on its last line: per-tick compute time
(wall: p50, p99, max, ms; and the loop thread's CPU time, p50 and p99, ms,
which leaves out time the thread spent preempted or waiting for the GIL), the
same tick run 200 times back to back (``tick_warm_ms_p50``: the code's own cost
with warm caches) and tick start jitter p99 (ms) per team size.

Why both: code that has not run for a few tens of milliseconds runs several
times slower, also after a busy wait instead of a pause, and the 4 Hz loop
always runs after such a pause (figures: docs/performance.md, "Why the loop
figure stays above the warm one").

Also for scale: the cost of one small numpy call back to back and 50 ms after
the previous one (``numpy_call_us_*``). Whatever ran in between evicted the
caches; the tick's cost after the pause is therefore about the number of
distinct calls it makes, which is why its numeric work is in a few compiled
kernels and it has no Python loop over the vehicles but the one that
publishes their setpoints.

For scale, it first measures how late a bare ``time.sleep`` loop wakes on
this machine (p99, ms): the floor under any jitter figure. It measures the
same again in a separate process while each team size runs
(``sleep_floor_loaded_ms_p99``): the floor under the load of the GCS and the
vehicles' process, which is what the loop's jitter competes with.

Targets: at most 1 ms per tick for 100 vehicles; jitter p99 at most 2 ms.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import yaml

from gcs.app import GcsApp, free_tcp_port
from gcs.config import ensure_team_key, load_team
from gcs.loop import Phase
from gcs.transport import ZenohSettings, open_session
from gcs.wire import MavlinkEncoder, SigningKey, keys
from sim import LIFT_LAG_S, BackgroundStepping

ROOT = Path(__file__).resolve().parents[1]
_TELEMETRY_PERIOD_S = 0.05
_BACKGROUND = "--vehicles-in-background"


def ring_team(n: int, folder: Path) -> Path:
    """A rigid ring of n vehicles (ring plus chords to the next-but-one), as a team file."""
    radius = max(1.0, 0.6 * n / (2 * math.pi))
    vehicles = [{"id": i + 1, "position": [radius * math.cos(2 * math.pi * i / n),
                                           radius * math.sin(2 * math.pi * i / n)]}
                for i in range(n)]
    pairs = {frozenset((i + 1, (i + k) % n + 1)) for i in range(n) for k in (1, 2)}
    edges = [sorted(p) for p in sorted(pairs, key=sorted)]
    team = {"name": f"ring{n}", "airframe": str(ROOT / "configs/airframes/bebop2.yaml"),
            "vehicles": vehicles, "edges": edges,
            "guidance": {"c1": 0.17, "c2": 0.3, "rate_hz": 4.0, "max_speed": 1.0,
                         "max_rotation_disagreement": 0.2, "scale_min": 1.0},
            "limits": {"bank_deg": 20.0, "accel_norm": 1.0, "accel_axis": 0.7},
            "payload": {"mass": 0.1, "rope_length": radius * 1.5},
            "analysis": {"max_distance_error": 1.0, "design_rope_angle_deg": 45.0},
            # long ropes: the lift (1 m above where they go taut, even shrunk) fits below
            "operator": {"altitude_max": math.ceil(radius * 1.5) + 3.0},
            "safety": {"geofence_xy": 1000.0,
                       "geofence_altitude": math.ceil(radius * 1.5) + 3.0},
            # the vehicles sign their frames with the team key, as the simulator's do: the
            # GCS refuses unsigned ones, and would measure a team it never hears
            "gcs": {"fleet": f"bench{n}", "team_key": str(folder / "team.key")}}
    path = folder / f"ring{n}.yaml"
    path.write_text(yaml.safe_dump(team))
    return path


def play_vehicles(session, fleet: str, positions: np.ndarray, stop: threading.Event,  # type: ignore[no-untyped-def]
                  *, key: SigningKey | None = None, background: bool = False) -> None:
    """Publish each vehicle's telemetry at 20 Hz until ``stop`` (``background``: as a sim
    host with ``--background`` steps)."""
    n = len(positions)
    pubs = [session.declare_publisher(keys.mavlink(fleet, i + 1, keys.Direction.FROM_VEHICLE))
            for i in range(n)]
    encs = [MavlinkEncoder(system_id=i + 1, component_id=1, signing_key=key) for i in range(n)]
    t0 = time.monotonic()
    due = [t0]
    priority = BackgroundStepping(lag_s=LIFT_LAG_S)
    if background:
        priority.start()
    priority.set_due(due[0])
    while not stop.is_set():
        ms = int((time.monotonic() - t0) * 1000)
        for i, (pub, enc) in enumerate(zip(pubs, encs, strict=True)):
            x, y = positions[i]
            # one payload per vehicle and period, as the sim host sends what is due
            pub.put(enc.encode(enc.mav.heartbeat_encode(2, 0, 129, 4, 4))
                    + enc.encode(enc.mav.local_position_ned_encode(ms, x, y, -1.5, 0.1, 0.0, 0.0))
                    + enc.encode(enc.mav.attitude_encode(ms, 0.01, 0.02, 0.0, 0.0, 0.0, 0.0)))
        due[0] += _TELEMETRY_PERIOD_S
        priority.set_due(due[0])
        if due[0] > time.monotonic():
            priority.keeping_up()
        stop.wait(max(0.0, due[0] - time.monotonic()))
    priority.close()


def measure(n: int, seconds: float, folder: Path, *,
            background: bool = False) -> dict[str, float]:
    path = ring_team(n, folder)
    ensure_team_key(folder / "team.key")  # made once, before both processes read it
    team = load_team(path)
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    # the vehicles play in another process, as they would on the network
    player = subprocess.Popen([sys.executable, __file__, "--play", str(path), endpoint,
                               *([_BACKGROUND] if background else [])])
    try:
        with GcsApp(team, zenoh_settings=ZenohSettings(mode="peer", connect=(endpoint,))) as app:
            deadline = time.monotonic() + 10
            while len(app.links.missing()) and time.monotonic() < deadline:
                time.sleep(0.05)
            app.runtime.phases.set(Phase.FORMATION)  # measure the streaming tick itself
            app.operator.set_sticks(0.5, 0.2, 0.3, now=app.clock.now(), source="bench")
            # The same tick back to back: the code's own cost with warm caches.
            warm = []
            for _ in range(200):
                t0 = time.perf_counter()
                app.runtime.tick()
                warm.append(time.perf_counter() - t0)
            compute: list[tuple[float, float]] = []
            app.add_listener(lambda snap, _t: compute.append((snap.compute_time,
                                                              snap.compute_cpu)))
            floor = subprocess.Popen([sys.executable, __file__, "--floor", str(seconds - 1.0)],
                                     stdout=subprocess.PIPE, text=True)
            app.start()
            time.sleep(seconds)
            stats = app.runtime.stats()
            loaded_floor = json.loads(floor.communicate(timeout=30)[0])
    finally:
        player.terminate()
        player.wait(timeout=5)
    c, cpu = (np.array(compute[2:]) * 1e3).T
    return {"ticks": len(c), "tick_ms_p50": round(float(np.percentile(c, 50)), 3),
            "tick_ms_p99": round(float(np.percentile(c, 99)), 3),
            "tick_ms_max": round(float(c.max()), 3),
            "tick_cpu_ms_p50": round(float(np.percentile(cpu, 50)), 3),
            "tick_cpu_ms_p99": round(float(np.percentile(cpu, 99)), 3),
            "tick_warm_ms_p50": round(float(np.percentile(warm, 50)) * 1e3, 3),
            "jitter_ms_p99": round(stats.jitter_p99 * 1e3, 3),
            "sleep_floor_loaded_ms_p99": loaded_floor}


def play(path: str, endpoint: str, background: bool) -> None:
    """The vehicles' process: listen on ``endpoint`` and publish telemetry until killed."""
    team = load_team(path)
    session = open_session(ZenohSettings(mode="peer", listen=(endpoint,), connect=()))
    rng = np.random.default_rng(0)
    positions = team.formation.positions + rng.normal(0, 0.05, team.formation.positions.shape)
    key, _ = ensure_team_key(Path(path).parent / "team.key")  # where ring_team points
    play_vehicles(session, team.config.gcs.fleet, positions, threading.Event(), key=key,
                  background=background)


def sleep_floor(seconds: float = 2.0, period: float = 0.02) -> float:
    """p99 of how late a bare sleep loop wakes, ms: the machine's own scheduling noise."""
    late = []
    start = time.monotonic()
    for k in range(1, int(seconds / period)):
        due = start + k * period
        time.sleep(max(0.0, due - time.monotonic()))
        late.append(time.monotonic() - due)
    return round(float(np.percentile(late, 99)) * 1e3, 3)


def numpy_call_cost(pause: float, count: int = 40) -> float:
    """Median cost of one small numpy call (us) made ``pause`` s after the previous one."""
    a = np.zeros(100)
    costs = []
    for _ in range(count):
        time.sleep(pause)
        t0 = time.perf_counter()
        np.add(a, 1.0)
        costs.append(time.perf_counter() - t0)
    return round(float(np.median(costs)) * 1e6, 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("seconds", nargs="?", type=float, default=30.0,
                        help="wall seconds measured per team size (default 30)")
    parser.add_argument(_BACKGROUND, dest="background", action="store_true",
                        help="the vehicles' process publishes as `gcs sim --background` steps")
    # the script's own child processes
    parser.add_argument("--play", nargs=2, metavar=("TEAM", "ENDPOINT"), help=argparse.SUPPRESS)
    parser.add_argument("--floor", type=float, metavar="S", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.play is not None:
        play(args.play[0], args.play[1], background=args.background)
        return
    if args.floor is not None:
        print(json.dumps(sleep_floor(args.floor)))
        return
    background, seconds = args.background, args.seconds
    out: dict[str, object] = {"sleep_floor_ms_p99": sleep_floor(),
                              "numpy_call_us_back_to_back": numpy_call_cost(0.0),
                              "numpy_call_us_after_50ms_sleep": numpy_call_cost(0.05),
                              "vehicles_in_background": background}
    print(f"bare sleep loop wakes late by up to {out['sleep_floor_ms_p99']} ms (p99)",
          file=sys.stderr)
    with tempfile.TemporaryDirectory() as tmp:
        for n in (4, 100):
            out[f"vehicles_{n}"] = measure(n, seconds, Path(tmp), background=background)
            print(f"{n} vehicles: {out[f'vehicles_{n}']}", file=sys.stderr)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
