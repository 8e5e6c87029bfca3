"""Flights through a busy machine and a bad second: a paced simulator and a GCS joined to it.

Each run starts the simulated team at 1x on the wall clock (``python -m sim``,
as ``gcs sim`` does), CPU hogs beside it, then ``gcs fly --connect`` with the
scenario (default: the paper's flight) and reads its JSON line. Optionally it
stops the simulator (SIGSTOP) for ``--stop-sim`` seconds when the first step
of formation flight starts, and the GCS process itself for ``--stop-gcs``
seconds when a later step starts (a stall no thread of it survives: the
vehicles drop to hold and the GCS must bring them back). With ``--link
DELAY_MS,LOSS_PCT`` the GCS reaches the simulator through a TCP relay that
delays every byte by DELAY_MS each way and, for LOSS_PCT % of the 10 ms
slices of traffic, holds the stream for a retransmission timeout (200 ms), as
TCP over a lossy radio does (the kernel here has no netem).

Prints a line per run, then one JSON object on the last line:

    {"runs": 5, "completed": 5, "offboard_exits": [0, ...], "recoveries": [...],
     "loop_stall_max_s": [...], "setpoint_gap_max_s": [...],
     "worst_distance_error_m": [...], "errors": [...]}

Exit status 1 unless every run completed with the payload lifted and set down.

    python bench/continuity.py [--runs 5] [--hogs 2] [--stop-sim 1.5] [--stop-gcs 0.8]
                               [--link 100,5] [--config C] [--scenario S]
"""

from __future__ import annotations

import argparse
import json
import os
import random
import selectors
import signal
import socket
import subprocess
import sys
import threading
import time
from collections import deque
from pathlib import Path

from gcs.app import free_tcp_port

ROOT = Path(__file__).resolve().parents[1]
FORMATION_STEP = "forward at 1 m/s"
"""The paper flight's first step of formation flight: the simulator is stopped there."""
GCS_STOP_STEP = "spin"
"""A later step: the GCS is stopped there."""
RTO_S = 0.2
"""TCP's minimum retransmission timeout on Linux, s: what one lost segment costs the stream."""


def hogs(count: int) -> list[subprocess.Popen[bytes]]:
    """``count`` processes that each keep a core busy."""
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(count)]


class Relay:
    """A TCP relay that delays each direction by ``delay`` s and stalls it on emulated loss."""

    def __init__(self, target: tuple[str, int], delay: float, loss: float, seed: int) -> None:
        self.target, self.delay, self.loss = target, delay, loss
        self._rng = random.Random(seed)
        self._server = socket.create_server(("127.0.0.1", 0))
        self.port = self._server.getsockname()[1]
        self._stop = threading.Event()
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        self._server.settimeout(0.2)
        while not self._stop.is_set():
            try:
                client, _ = self._server.accept()
            except TimeoutError:
                continue
            upstream = socket.create_connection(self.target)
            for a, b in ((client, upstream), (upstream, client)):
                threading.Thread(target=self._pipe, args=(a, b), daemon=True).start()

    def _pipe(self, src: socket.socket, dst: socket.socket) -> None:
        """Bytes from ``src`` reach ``dst`` ``delay`` later; a lost slice holds the stream."""
        queue: deque[tuple[float, bytes]] = deque()
        lock = threading.Condition()
        closed = threading.Event()

        def send() -> None:
            held_until = 0.0
            while True:
                with lock:
                    while not queue and not closed.is_set():
                        lock.wait(0.05)
                    if not queue:
                        return
                    due, data = queue[0]
                wait = max(due, held_until) - time.monotonic()
                if wait > 0:
                    time.sleep(min(wait, 0.01))
                    continue
                with lock:
                    queue.popleft()
                if self._rng.random() < self.loss:  # this slice was lost: resent after RTO
                    held_until = time.monotonic() + RTO_S
                try:
                    dst.sendall(data)
                except OSError:
                    return

        threading.Thread(target=send, daemon=True).start()
        sel = selectors.DefaultSelector()
        sel.register(src, selectors.EVENT_READ)
        while not self._stop.is_set():
            if not sel.select(0.2):
                continue
            try:
                data = src.recv(65536)
            except OSError:
                data = b""
            if not data:
                break
            with lock:
                queue.append((time.monotonic() + self.delay, data))
                lock.notify()
        closed.set()

    def close(self) -> None:
        self._stop.set()
        self._server.close()


def start_sim(config: str, endpoint: str) -> subprocess.Popen[str]:
    sim = subprocess.Popen([sys.executable, "-m", "sim", "--config", config, "--listen",
                            endpoint, "--speed", "1"], cwd=ROOT, stdout=subprocess.PIPE,
                           stderr=subprocess.DEVNULL, text=True)
    out = sim.stdout
    assert out is not None
    for line in out:
        if line.startswith("sim ready"):
            break
    threading.Thread(target=out.read, daemon=True).start()  # drain: the pipe must not fill
    return sim


def pause(proc: subprocess.Popen[str], seconds: float) -> None:
    os.kill(proc.pid, signal.SIGSTOP)
    time.sleep(seconds)
    os.kill(proc.pid, signal.SIGCONT)


def one_run(args: argparse.Namespace, k: int, record: Path) -> dict[str, object]:
    port = free_tcp_port()
    sim = start_sim(args.config, f"tcp/127.0.0.1:{port}")
    relay = None
    connect = f"tcp/127.0.0.1:{port}"
    if args.link:
        delay_ms, loss_pct = (float(x) for x in args.link.split(","))
        relay = Relay(("127.0.0.1", port), delay_ms / 1e3, loss_pct / 100.0, seed=k)
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
                                  "link": args.link or None,
                                  "completed": sum(bool(m["ok"]) for m in results)}
    summary |= {key: [m.get(key) for m in results] for key in keys}
    print(json.dumps(summary))
    return 0 if summary["completed"] == args.runs else 1


if __name__ == "__main__":
    sys.exit(main())
