"""Round-trip latency of one setpoint: GCS link -> zenoh -> sim host -> echo -> GCS link.

Starts the sim host (``python -m sim``) as a separate process on a free
loopback port, opens a :class:`gcs.link.Link` to vehicle 1 over a real zenoh
peer session, then sends SET_POSITION_TARGET_LOCAL_NED setpoints one at a
time and waits for each one's POSITION_TARGET_LOCAL_NED echo. Each round
trip crosses two processes and zenoh twice and includes MAVLink encoding and
decoding on both sides, the host's checks and its autopilot call; the host
keeps running its physics at real-time speed (4 vehicles, full telemetry)
meanwhile. The setpoints go to a disarmed vehicle, which accepts and echoes
them without flying.

For scale on a shared machine it first measures the floor: the same number
of bare zenoh round trips between this process and a minimal echo process
(one Python callback each way, no MAVLink, no simulation).

Prints summary lines, then one JSON object on the last line::

    {"count": 2000, "p50_ms": ..., "p99_ms": ..., "max_ms": ...,
     "zenoh_floor_p50_ms": ..., "zenoh_floor_p99_ms": ..., "target_p99_ms": 1.0}

    python bench/link_latency.py [--count 2000] [--config configs/bebop_square.yaml]
"""

from __future__ import annotations

import argparse
import json
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

from gcs.link import Link, MavMessage, ZenohSettings, ZenohTransport, open_session

__all__ = ["main"]

_ROOT = Path(__file__).resolve().parent.parent
_FLEET = "latency-bench"
_SYSID = 1
_WARMUP = 50
_TIMEOUT_S = 2.0
_TARGET_P99_MS = 1.0


_ECHO = """
import sys
from gcs.link import ZenohSettings, open_session
session = open_session(ZenohSettings(listen=(sys.argv[1],), connect=()))
pong = session.declare_publisher("bench/pong", express=True)
ping = session.declare_subscriber("bench/ping", lambda s: pong.put(s.payload.to_bytes()))
print("ready", flush=True)
sys.stdin.read()
ping.undeclare()
session.close()
"""
"""A minimal zenoh echo process: the floor under any round trip between two processes."""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class _Echoes:
    """Wakes the sender when the echo of setpoint ``expected`` arrives."""

    def __init__(self) -> None:
        self.expected = -1
        self.event = threading.Event()

    def on_message(self, msg: MavMessage) -> None:
        if msg.get_type() == "POSITION_TARGET_LOCAL_NED" and round(msg.afy * 1000) == \
                self.expected:
            self.event.set()


def _round_trips(link: Link, count: int) -> np.ndarray:
    echoes = _Echoes()
    link.add_message_listener(echoes.on_message)
    out = np.empty(count)
    for k in range(-_WARMUP, count):
        tag = k % 1000  # afy = tag / 1000 m/s^2 identifies the echo (float32 keeps it exact)
        echoes.expected = tag
        echoes.event.clear()
        start = time.perf_counter()
        link.send_setpoint(accel_xy_ned=(0.0, tag / 1000.0), z_ned=-1.0)
        if not echoes.event.wait(_TIMEOUT_S):
            raise RuntimeError(f"no echo of setpoint {k} within {_TIMEOUT_S} s")
        if k >= 0:
            out[k] = time.perf_counter() - start
    return out * 1000.0


def _zenoh_floor(count: int) -> np.ndarray:
    """Round trips (ms) of a 60-byte payload to the echo process and back."""
    endpoint = f"tcp/127.0.0.1:{_free_port()}"
    echo = subprocess.Popen([sys.executable, "-c", _ECHO, endpoint], cwd=_ROOT,
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert echo.stdout is not None and echo.stdin is not None
        if echo.stdout.readline().strip() != "ready":
            raise RuntimeError(f"echo process did not start (exit {echo.poll()})")
        session = open_session(ZenohSettings(connect=(endpoint,)))
        got = threading.Event()
        pong = session.declare_subscriber("bench/pong", lambda _: got.set())
        ping = session.declare_publisher("bench/ping", express=True)
        try:
            payload = bytes(60)
            while not got.is_set():  # until the route is up
                ping.put(payload)
                got.wait(0.05)
            out = np.empty(count)
            for k in range(-_WARMUP, count):
                got.clear()
                start = time.perf_counter()
                ping.put(payload)
                if not got.wait(_TIMEOUT_S):
                    raise RuntimeError(f"no echo of ping {k} within {_TIMEOUT_S} s")
                if k >= 0:
                    out[k] = time.perf_counter() - start
        finally:
            pong.undeclare()
            ping.undeclare()
            session.close()
        echo.stdin.close()
        echo.wait(timeout=10.0)
    finally:
        if echo.poll() is None:
            echo.kill()
            echo.wait()
    return out * 1000.0


def main() -> int:
    """Run the benchmark; returns the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--count", type=int, default=2000, help="measured round trips")
    parser.add_argument("--config", default=str(_ROOT / "configs" / "bebop_square.yaml"),
                        help="team file for the sim host")
    args = parser.parse_args()
    floor = _zenoh_floor(args.count)
    endpoint = f"tcp/127.0.0.1:{_free_port()}"
    sim = subprocess.Popen(
        [sys.executable, "-m", "sim", "--config", args.config, "--listen", endpoint,
         "--fleet", _FLEET], cwd=_ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
        text=True)
    try:
        assert sim.stdout is not None
        ready = sim.stdout.readline().strip()
        if not ready.startswith("sim ready:"):
            raise RuntimeError(f"sim host did not start (exit {sim.poll()})")
        session = open_session(ZenohSettings(connect=(endpoint,)))
        try:
            link = Link(_SYSID, ZenohTransport.for_gcs(session, fleet=_FLEET, sysid=_SYSID),
                        gcs_heartbeat_period_s=0.0, timesync_period_s=0.0).start()
            try:
                link.wait_for(lambda t: t.heartbeat is not None, timeout_s=10.0,
                              what="the first HEARTBEAT")
                ms = _round_trips(link, args.count)
            finally:
                link.close()
        finally:
            session.close()
    finally:
        sim.terminate()
        sim.wait(timeout=10.0)
    p50, p99 = np.percentile(ms, [50.0, 99.0])
    f50, f99 = np.percentile(floor, [50.0, 99.0])
    print(f"{ready}\nbare zenoh round trip (floor): p50 {f50:.3f} ms, p99 {f99:.3f} ms\n"
          f"setpoint round trip over zenoh: {args.count} samples, p50 {p50:.3f} ms, "
          f"p99 {p99:.3f} ms, max {ms.max():.3f} ms (target p99 <= {_TARGET_P99_MS} ms)")
    print(json.dumps({"count": int(args.count), "p50_ms": round(float(p50), 4),
                      "p99_ms": round(float(p99), 4), "max_ms": round(float(ms.max()), 4),
                      "zenoh_floor_p50_ms": round(float(f50), 4),
                      "zenoh_floor_p99_ms": round(float(f99), 4),
                      "target_p99_ms": _TARGET_P99_MS}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
