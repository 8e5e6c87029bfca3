"""Flights through a busy machine and a bad second: a paced simulator and a GCS joined to it.

Each run starts the simulated team at 1x on the wall clock (``python -m sim``,
as ``gcs sim`` does), CPU hogs beside it, then ``gcs fly --connect`` with the
scenario (default: the paper's flight) and reads its JSON line. Optionally it
stops the simulator (SIGSTOP) for ``--stop-sim`` seconds when the first step
of formation flight starts, and the GCS process itself for ``--stop-gcs``
seconds when a later step starts (a stall no thread of it survives: the
vehicles drop to hold and the GCS must bring them back). With ``--netns`` the
simulator runs on a second host (a network namespace joined by a veth pair,
needs root). With ``--link DELAY_MS,LOSS_PCT`` the GCS reaches the simulator
through :class:`gcs.testing.LossyRelay`: DELAY_MS each way and, for LOSS_PCT
% of the chunks, a stall of a retransmission timeout, as TCP over a lossy
radio behaves (a kernel without netem cannot drop on the veth itself).

Prints a line per run, then one JSON object on the last line:

    {"runs": 5, "completed": 5, "offboard_exits": [0, ...], "recoveries": [...],
     "loop_stall_max_s": [...], "setpoint_gap_max_s": [...],
     "worst_distance_error_m": [...], "errors": [...]}

Exit status 1 unless every run completed with the payload lifted and set down.

    python bench/continuity.py [--runs 5] [--hogs 2] [--stop-sim 1.5] [--stop-gcs 0.8]
                               [--netns] [--link 100,5] [--config C] [--scenario S]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from gcs.app import free_tcp_port
from gcs.testing import Host, LossyRelay

ROOT = Path(__file__).resolve().parents[1]
FORMATION_STEP = "forward at 1 m/s"
"""The paper flight's first step of formation flight: the simulator is stopped there."""
GCS_STOP_STEP = "spin"
"""A later step: the GCS is stopped there."""


def hogs(count: int) -> list[subprocess.Popen[bytes]]:
    """``count`` processes that each keep a core busy."""
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]


def start_sim(config: str, endpoint: str, host: Host | None) -> subprocess.Popen[str]:
    argv = [sys.executable, "-m", "sim", "--config", config, "--listen", endpoint,
            "--speed", "1"]
    sim = subprocess.Popen(argv if host is None else host.command(*argv), cwd=ROOT,
                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    out = sim.stdout
    assert out is not None
    for line in out:
        if line.startswith("sim ready"):
            break
    threading.Thread(target=out.read, daemon=True).start()  # drain: the pipe must not fill
    return sim


def pause(proc: subprocess.Popen[str], seconds: float) -> None:
    """Stop a process and its children (``ip netns exec`` runs the simulator as a child)."""
    pids = [proc.pid, *children(proc.pid)]
    for pid in pids:
        os.kill(pid, signal.SIGSTOP)
    time.sleep(seconds)
    for pid in pids:
        os.kill(pid, signal.SIGCONT)


def children(pid: int) -> list[int]:
    with contextlib.suppress(OSError), open(f"/proc/{pid}/task/{pid}/children") as f:
        return [int(c) for c in f.read().split()]
    return []


def one_run(args: argparse.Namespace, k: int, record: Path) -> dict[str, object]:
    port = free_tcp_port()
    host = Host() if args.netns else None
    address = "127.0.0.1" if host is None else host.address
    sim = start_sim(args.config, f"tcp/{address}:{port}", host)
    relay = None
    connect = f"tcp/{address}:{port}"
    if args.link:
        delay_ms, loss_pct = (float(x) for x in args.link.split(","))
        relay = LossyRelay((address, port), delay=delay_ms / 1e3, loss=loss_pct / 100.0,
                           seed=k)
        connect = f"tcp/127.0.0.1:{relay.port}"
    busy = hogs(args.hogs)
    try:
        fly = subprocess.Popen([sys.executable, "-m", "gcs", "fly", "--config", args.config,
                                "--scenario", args.scenario, "--connect", connect, "--json",
                                "--record", str(record)], cwd=ROOT, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
        assert fly.stderr is not None
        stops: list[str] = []
        for line in fly.stderr:
            if args.stop_sim and FORMATION_STEP in line and "sim" not in stops:
                stops.append("sim")
                pause(sim, args.stop_sim)
            elif args.stop_gcs and GCS_STOP_STEP in line and "gcs" not in stops:
                stops.append("gcs")
                time.sleep(2.0)  # into the spin
                pause(fly, args.stop_gcs)
        out, _ = fly.communicate(timeout=600)
    finally:
        for h in busy:
            h.kill()
        sim.terminate()
        sim.wait(10)
        if relay is not None:
            relay.close()
        if host is not None:
            host.close()
    try:
        return dict(json.loads(out.strip().splitlines()[-1]))
    except (ValueError, IndexError):
        return {"completed": False, "error": f"no JSON from gcs fly (exit {fly.returncode})"}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--hogs", type=int, default=2, help="CPU hogs beside the flight")
    parser.add_argument("--stop-sim", type=float, default=0.0, metavar="S",
                        help="SIGSTOP the simulator for S s in formation flight")
    parser.add_argument("--stop-gcs", type=float, default=0.0, metavar="S",
                        help="SIGSTOP the GCS for S s later in the flight")
    parser.add_argument("--netns", action="store_true",
                        help="run the simulator on a second host (network namespace; root)")
    parser.add_argument("--link", default="", metavar="DELAY_MS,LOSS_PCT",
                        help="reach the simulator through a delaying, lossy TCP relay")
    parser.add_argument("--config", default="configs/bebop_square.yaml")
    parser.add_argument("--scenario", default="configs/scenarios/paper_flight.yaml")
    parser.add_argument("--out", type=Path, default=Path("/tmp/continuity"),
                        help="folder for the runs' .tlog files")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    results = []
    for k in range(args.runs):
        m = one_run(args, k, args.out / f"run{k + 1}.tlog")
        phases = m.get("phases")
        lift = m.get("payload_lift_m")
        ok = bool(m.get("completed")) and isinstance(lift, float) and lift > 0.8 \
            and isinstance(phases, list) and "setting down" in phases
        m["ok"] = ok
        results.append(m)
        print(f"run {k + 1}: {'completed' if ok else 'FAILED'}; offboard exits "
              f"{m.get('offboard_exits')}, recoveries {m.get('recoveries')}, loop stall max "
              f"{m.get('loop_stall_max_s')} s, setpoint gap max {m.get('setpoint_gap_max_s')} s, "
              f"worst distance error {m.get('worst_distance_error_m')} m"
              + (f"; {m.get('error')}" if m.get("error") else ""), flush=True)
    keys = ("offboard_exits", "recoveries", "loop_stall_max_s", "setpoint_gap_max_s",
            "worst_distance_error_m", "payload_lift_m", "error")
    summary: dict[str, object] = {"runs": args.runs, "hogs": args.hogs,
                                  "stop_sim_s": args.stop_sim, "stop_gcs_s": args.stop_gcs,
                                  "netns": args.netns, "link": args.link or None,
                                  "completed": sum(bool(m["ok"]) for m in results)}
    summary |= {key: [m.get(key) for m in results] for key in keys}
    print(json.dumps(summary))
    return 0 if summary["completed"] == args.runs else 1


if __name__ == "__main__":
    sys.exit(main())
