"""Round-trip latency of one setpoint: GCS link -> zenoh -> sim host -> echo -> GCS link.

Starts the sim host (``python -m sim``) as a separate process on a free
loopback port, opens a :class:`gcs.link.Link` to vehicle 1 over a real zenoh
peer session, then sends SET_POSITION_TARGET_LOCAL_NED setpoints one at a
time and waits for each one's POSITION_TARGET_LOCAL_NED echo. Each round
trip crosses two processes and zenoh twice and includes MAVLink encoding and
decoding on both sides, the host's checks and its autopilot call; the host
keeps running its physics at real-time speed (4 vehicles, full telemetry)
meanwhile. The setpoints go to a disarmed vehicle, which accepts and echoes
them without flying. This process gives receive threads the GIL within
0.1 ms, as the GCS process does (``gcs.app.LOOP_GIL_SWITCH_S``).

For scale on a shared machine it measures the floor at the same moments:
each setpoint round trip is followed by a bare zenoh round trip between this
process and a minimal echo process (one Python callback each way, no
MAVLink, no simulation), so both see the same load.

It runs twice: with the sim host as started by default, then with
``--background`` (the host steps at background CPU priority, see
sim/README.md), whose keys carry a ``background_`` prefix. Frames are signed
with the team key, as the sim host and the GCS do by default. Prints summary
lines, then one JSON object on the last line::

    {"count": 2000, "target_p99_ms": 1.0, "p50_ms": ..., "p99_ms": ..., "max_ms": ...,
     "zenoh_floor_p50_ms": ..., "zenoh_floor_p99_ms": ...,
     "background_p50_ms": ..., "background_p99_ms": ..., ...}

    python bench/link_latency.py [--count 2000] [--config configs/bebop_square.yaml]

With ``--tls`` it compares plain TCP with zenoh over TLS with mutual
authentication and access control by role (certificates made as ``gcs
certs`` does, in a temporary folder): both runs with the sim host as started
by default, alternating ``--rounds`` times (default 2) so that a busy moment of
the machine does not fall on one side only; the TLS keys carry a ``tls_``
prefix, and ``tls_ratio_p50``, ``tls_ratio_p99`` (target <= 1.5) compare the
pooled setpoint round trips.
"""

from __future__ import annotations

import argparse
import functools
import json
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import zenoh

from gcs.app import LOOP_GIL_SWITCH_S
from gcs.config import default_team_key_path, ensure_team_key
from gcs.link import Link
from gcs.transport import (
    TlsSettings,
    ZenohSettings,
    ZenohTransport,
    make_team_certificates,
    open_session,
)
from gcs.wire import MavMessage, keys

__all__ = ["main"]

_ROOT = Path(__file__).resolve().parent.parent
_FLEET = "latency-bench"
_SYSID = 1
_WARMUP = 50
_TIMEOUT_S = 2.0
_TARGET_P99_MS = 1.0
_TARGET_TLS_RATIO = 1.5
_ECHO_SYSID = 200
"""The echo process answers on this vehicle's keys, which the access control lets a GCS
publish to and a sim answer on, like the setpoints' own."""


_ECHO = """
import sys
from gcs.transport import TlsSettings, ZenohSettings, open_session
from gcs.wire import keys
endpoint, fleet, sysid, certs = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
tls = TlsSettings(dir=certs, role="sim") if certs else None
session = open_session(ZenohSettings(listen=(endpoint,), connect=(), tls=tls))
pong = session.declare_publisher(keys.mavlink(fleet, sysid, keys.Direction.FROM_VEHICLE),
                                 express=True)
ping = session.declare_subscriber(keys.mavlink(fleet, sysid, keys.Direction.TO_VEHICLE),
                                  lambda s: pong.put(s.payload.to_bytes()))
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


class _Pongs:
    """Wakes the sender when the bare echo process answers."""

    def __init__(self) -> None:
        self.event = threading.Event()

    def on_sample(self, _sample: object) -> None:
        self.event.set()


def _timed(send: Callable[[], None], event: threading.Event, what: str) -> float:
    event.clear()
    start = time.perf_counter()
    send()
    if not event.wait(_TIMEOUT_S):
        raise RuntimeError(f"no answer to {what} within {_TIMEOUT_S} s")
    return time.perf_counter() - start


def _round_trips(link: Link, ping: zenoh.Publisher, pongs: _Pongs,
                 count: int) -> tuple[np.ndarray, np.ndarray]:
    """Setpoint round trips and bare zenoh round trips, interleaved one for one (ms).

    Interleaving puts both under the same machine load at the same moments, so
    the floor is the floor of these very samples.
    """
    echoes = _Echoes()
    link.add_message_listener(echoes.on_message)
    payload = bytes(60)
    setpoints, floor = np.empty(count), np.empty(count)
    for k in range(-_WARMUP, count):
        tag = k % 1000  # afy = tag / 1000 m/s^2 identifies the echo (float32 keeps it exact)
        echoes.expected = tag
        rtt = _timed(functools.partial(link.send_setpoint, accel_xy_ned=(0.0, tag / 1000.0),
                                       z_ned=-1.0), echoes.event, f"setpoint {k}")
        bare = _timed(lambda: ping.put(payload), pongs.event, f"ping {k}")
        if k >= 0:
            setpoints[k], floor[k] = rtt, bare
    return setpoints * 1000.0, floor * 1000.0


def _start(args: list[str], ready_prefix: str, what: str) -> tuple[subprocess.Popen[str], str]:
    proc = subprocess.Popen(args, cwd=_ROOT, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    assert proc.stdout is not None and proc.stderr is not None
    line = proc.stdout.readline().strip()
    if not line.startswith(ready_prefix):
        proc.kill()
        said = proc.stderr.read().strip().splitlines()
        raise RuntimeError(f"{what} did not start (exit {proc.wait()}): "
                           f"{said[-1] if said else 'nothing on stderr'}")
    threading.Thread(target=proc.stderr.read, daemon=True).start()  # a full pipe must not block it
    return proc, line


def _stop(proc: subprocess.Popen[str]) -> None:
    proc.terminate()
    try:
        proc.wait(timeout=10.0)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def _measure(config: str, count: int, sim_options: list[str],
             certs: Path | None = None) -> tuple[str, np.ndarray, np.ndarray]:
    """Start the sim host (with ``sim_options``) and the echo process; both series, ms.
    With ``certs`` every session is TLS with mutual authentication and access control."""
    proto = "tcp" if certs is None else "tls"
    sim_endpoint = f"{proto}/127.0.0.1:{_free_port()}"
    echo_endpoint = f"{proto}/127.0.0.1:{_free_port()}"
    tls_options = [] if certs is None else ["--tls", str(certs)]
    sim, ready = _start([sys.executable, "-m", "sim", "--config", config, "--listen",
                         sim_endpoint, "--fleet", _FLEET, *sim_options, *tls_options],
                        "sim ready:", "sim host")
    try:
        echo, _ = _start([sys.executable, "-c", _ECHO, echo_endpoint, _FLEET, str(_ECHO_SYSID),
                          str(certs or "")], "ready", "echo process")
        try:
            tls = None if certs is None else TlsSettings(dir=str(certs), role="gcs")
            session = open_session(ZenohSettings(connect=(sim_endpoint, echo_endpoint),
                                                 tls=tls))
            pongs = _Pongs()
            pong = session.declare_subscriber(
                keys.mavlink(_FLEET, _ECHO_SYSID, keys.Direction.FROM_VEHICLE), pongs.on_sample)
            ping = session.declare_publisher(
                keys.mavlink(_FLEET, _ECHO_SYSID, keys.Direction.TO_VEHICLE), express=True)
            try:
                while not pongs.event.is_set():  # until the route to the echo is up
                    ping.put(bytes(60))
                    pongs.event.wait(0.05)
                link = Link(_SYSID, ZenohTransport.for_gcs(session, fleet=_FLEET, sysid=_SYSID),
                            signing_key=ensure_team_key(default_team_key_path())[0],
                            gcs_heartbeat_period_s=0.0, timesync_period_s=0.0).start()
                try:
                    link.wait_for(lambda t: t.heartbeat is not None, timeout_s=10.0,
                                  what="the first HEARTBEAT")
                    ms, floor = _round_trips(link, ping, pongs, count)
                finally:
                    link.close()
            finally:
                pong.undeclare()
                ping.undeclare()
                session.close()
        finally:
            _stop(echo)
    finally:
        _stop(sim)
    return ready, ms, floor


def _plain_and_tls(config: str, count: int, rounds: int) -> dict[str, tuple[str, np.ndarray,
                                                                             np.ndarray]]:
    """Plain and TLS runs alternating ``rounds`` times; each side's samples pooled."""
    sides: dict[str, list[tuple[str, np.ndarray, np.ndarray]]] = {"": [], "tls_": []}
    with tempfile.TemporaryDirectory(prefix="link-latency-certs-") as folder:
        certs = Path(folder) / "certs"
        make_team_certificates(certs)
        for _ in range(rounds):
            sides[""].append(_measure(config, count, []))
            sides["tls_"].append(_measure(config, count, [], certs))
    return {prefix: (runs[0][0], np.concatenate([r[1] for r in runs]),
                     np.concatenate([r[2] for r in runs])) for prefix, runs in sides.items()}


def main() -> int:
    """Run the benchmark; returns the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--count", type=int, default=2000, help="measured round trips")
    parser.add_argument("--config", default=str(_ROOT / "configs" / "bebop_square.yaml"),
                        help="team file for the sim host")
    parser.add_argument("--tls", action="store_true",
                        help="compare plain TCP with TLS (mutual authentication and access "
                             "control) instead of the default and --background sim host")
    parser.add_argument("--rounds", type=int, default=2,
                        help="with --tls: plain and TLS runs, alternating (default 2)")
    args = parser.parse_args()
    # as in the GCS process (GcsApp.start): receive threads get the GIL within 0.1 ms
    sys.setswitchinterval(LOOP_GIL_SWITCH_S)
    if args.tls:
        runs = _plain_and_tls(args.config, args.count, max(1, args.rounds))
    else:
        runs = {"": _measure(args.config, args.count, []),
                "background_": _measure(args.config, args.count, ["--background"])}
    out: dict[str, float] = {"count": int(args.count), "target_p99_ms": _TARGET_P99_MS}
    for prefix, (ready, ms, floor) in runs.items():
        p50, p99 = np.percentile(ms, [50.0, 99.0])
        f50, f99 = np.percentile(floor, [50.0, 99.0])
        print(f"{ready}\n  bare zenoh round trip (floor): p50 {f50:.3f} ms, p99 {f99:.3f} ms\n"
              f"  setpoint round trip over zenoh: {len(ms)} samples, p50 {p50:.3f} ms, "
              f"p99 {p99:.3f} ms, max {ms.max():.3f} ms (target p99 <= {_TARGET_P99_MS} ms)")
        out |= {f"{prefix}p50_ms": round(float(p50), 4), f"{prefix}p99_ms": round(float(p99), 4),
                f"{prefix}max_ms": round(float(ms.max()), 4),
                f"{prefix}zenoh_floor_p50_ms": round(float(f50), 4),
                f"{prefix}zenoh_floor_p99_ms": round(float(f99), 4)}
    if args.tls:
        ratio50, ratio99 = (out[f"tls_{k}"] / out[k] for k in ("p50_ms", "p99_ms"))
        print(f"TLS / plain setpoint round trip: p50 {ratio50:.2f}x, p99 {ratio99:.2f}x "
              f"(target <= {_TARGET_TLS_RATIO}x)")
        out |= {"tls_ratio_p50": round(ratio50, 3), "tls_ratio_p99": round(ratio99, 3),
                "target_tls_ratio": _TARGET_TLS_RATIO}
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
