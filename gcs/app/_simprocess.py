"""Start the simulated team (``python -m sim``) as a child process and wait until it is up.

The GCS sees simulated vehicles only through zenoh, exactly as it would see a
``gcs sim`` started by hand on another machine; this module just saves the
operator that step for ``gcs demo`` and ``gcs fly``.
"""

from __future__ import annotations

import collections
import contextlib
import json
import os
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from gcs.app._simfork import ForkedSim, fork_server_enabled, fork_sim
from gcs.common import die_with_parent, to_mapping
from gcs.config import Team

__all__ = ["SimProcess", "SimStartError", "free_tcp_port"]


_FIRST_NOTE_S = 5.0
_NOTE_PERIOD_S = 15.0
_BUSY_WINDOW_S = 10.0
"""A simulator past its ready timeout still gets time while it used the CPU this recently."""
_BUSY_SHARE = 0.05
"""The share of one core over that window that says "working" (compiling), not "stuck"."""
_CEILING = 5.0
"""A busy simulator gets at most this many times its ready timeout."""


def cpu_seconds(pid: int) -> float | None:
    """CPU time a process has used, s (Linux ``/proc``); None where it cannot be read."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return None


class _Busy:
    """Whether a starting process is working (its CPU time grows), so that a first start
    that compiles its kernels on a loaded machine is not mistaken for a hung one.

    ``pid`` is asked at each sample: a forked simulator is its warming server until forked.
    """

    def __init__(self, pid: Callable[[], int]) -> None:
        self._pid = pid
        self._sampled: int | None = None
        self._samples: collections.deque[tuple[float, float]] = collections.deque()

    def sample(self, now: float) -> None:
        pid = self._pid()
        if pid != self._sampled:
            self._sampled = pid
            self._samples.clear()
        cpu = cpu_seconds(pid)
        if cpu is not None:
            self._samples.append((now, cpu))
            while len(self._samples) > 2 and now - self._samples[1][0] >= _BUSY_WINDOW_S:
                self._samples.popleft()

    def working(self) -> bool:
        if len(self._samples) < 2:
            return False
        (t0, c0), (t1, c1) = self._samples[0], self._samples[-1]
        return t1 > t0 and (c1 - c0) >= _BUSY_SHARE * (t1 - t0)

    def used(self) -> float | None:
        return self._samples[-1][1] if self._samples else None


_PORT_TAKEN = "Address already in use"
"""What a simulator says (zenoh's listener error) when its port was taken before it bound it."""


class SimStartError(RuntimeError):
    """The simulator did not come up; carries what it printed."""


def free_tcp_port() -> int:
    """A TCP port on 127.0.0.1 that was free a moment ago."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class SimProcess:
    """A running ``python -m sim``; use as a context manager (terminates it on exit).

    Args:
        config: team config file, or a loaded team: the simulator then flies it as it is
            in memory (its file's directory still anchors relative paths).
        endpoint: zenoh endpoint the sim listens on, e.g. ``tcp/127.0.0.1:7447``.
        speed: sim seconds per wall second, or ``"max"``.
        lockstep: let the GCS's clock acks pace the sim (headless, deterministic).
        signing: False starts it ``--insecure`` (no MAVLink signing).
        progress: told a line every few seconds while the simulator is not ready yet (its
            first start compiles its kernels, which can take a minute: not a hang).
        extra: more command-line arguments for the sim.
        fork_server: fork it from this process's warm simulator server (:mod:`gcs.app._simfork`:
            ready in tens of milliseconds once the server is up; ``GCS_SIM_FORK=0`` turns it
            off); False starts a fresh ``python -m sim``, as a process that starts only one
            should (the server costs what a cold start does).
        ready_timeout: how long to wait for its ready line, s; up to five times that
            while the simulator is working (its CPU time grows: a first start compiling
            its kernels on a loaded machine), so only an idle or runaway one is given up.
        wrap: turns the command into the one to run, e.g. on another host
            (:meth:`gcs.testing.Host.command`); it must exec the sim, not fork it.
    """

    def __init__(self, config: str | Path | Team, *, endpoint: str, speed: str = "1",
                 lockstep: bool = False, signing: bool = True, extra: tuple[str, ...] = (),
                 ready_timeout: float = 60.0,
                 wrap: Callable[..., list[str]] | None = None,
                 progress: Callable[[str], None] | None = None,
                 fork_server: bool = True) -> None:
        team_json: list[str] = []
        if isinstance(config, Team):
            team_json = ["--team-json", json.dumps(to_mapping(config.config))]
            config = config.source
        cmd = [sys.executable, "-m", "sim", "--config", str(config), *team_json,
               "--listen", endpoint,
               "--speed", speed, *(["--lockstep"] if lockstep else []),
               *([] if signing else ["--insecure"]), *extra]
        forked: ForkedSim | None = None
        if wrap is not None:
            cmd = wrap(*cmd)
        elif fork_server and fork_server_enabled():
            with contextlib.suppress(OSError):  # no server: a cold start, as without one
                forked = fork_sim(cmd[3:])
        self.endpoint = endpoint
        self._proc: subprocess.Popen[str] | ForkedSim = forked or subprocess.Popen(
            cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1,
            preexec_fn=die_with_parent)
        self._lines: queue.Queue[str] = queue.Queue()
        self._err: list[str] = []
        threading.Thread(target=self._pump, args=(self._proc.stdout, True), daemon=True).start()
        threading.Thread(target=self._pump, args=(self._proc.stderr, False),
                         daemon=True).start()
        start = time.monotonic()
        busy = _Busy(lambda: self._proc.pid)
        next_note = start + _FIRST_NOTE_S
        while True:
            try:
                line = self._lines.get(timeout=0.1)
            except queue.Empty:
                line = ""
            now = time.monotonic()
            busy.sample(now)
            if progress is not None and now >= next_note and not line.startswith("sim ready"):
                used = busy.used()
                cpu = "" if used is None else f", {used:.0f} s of CPU"
                progress(f"the simulator is still starting ({now - start:.0f} s{cpu}): its "
                         f"first start compiles its kernels, up to a minute on a free core; "
                         f"later starts load them")
                next_note = now + _NOTE_PERIOD_S
            if line.startswith("sim ready"):
                self.ready_line = line.strip()
                return
            late = now - start > ready_timeout
            if self._proc.poll() is not None or (late and not busy.working()) \
                    or now - start > _CEILING * ready_timeout:
                why = ("exited" if self._proc.returncode is not None
                       else f"was not ready after {now - start:.0f} s "
                            f"({'still busy' if busy.working() else 'idle'}: ready timeout "
                            f"{ready_timeout:g} s, {_CEILING:g}x that while it works)")
                self.close()
                detail = " | ".join(self._err[-5:]) or "no output"
                raise SimStartError(f"the simulator {why}: {detail}" if why[0] == "w"
                                    else f"the simulator {why} before it was ready: {detail}")

    @classmethod
    def on_free_port(cls, config: str | Path | Team, *, attempts: int = 3,
                     **options: Any) -> SimProcess:
        """A simulator listening on a free loopback port (its :attr:`endpoint`), with
        ``options`` as the constructor's. :func:`free_tcp_port` is free only a moment:
        another process may bind it before the simulator does (a seed's simulator lost
        its port so, flights running side by side on a loaded machine); then another
        port, up to ``attempts`` in all."""
        for attempt in range(1, attempts + 1):
            try:
                return cls(config, endpoint=f"tcp/127.0.0.1:{free_tcp_port()}", **options)
            except SimStartError as exc:
                if _PORT_TAKEN not in str(exc) or attempt == attempts:
                    raise
        raise AssertionError("unreachable")

    def _pump(self, stream: IO[str], to_queue: bool) -> None:
        for line in stream:
            if to_queue:
                self._lines.put(line)
            else:
                self._err.append(line.rstrip())

    @property
    def stderr_tail(self) -> list[str]:
        """The last lines the sim printed on stderr."""
        return self._err[-20:]

    def alive(self) -> bool:
        return self._proc.poll() is None

    def close(self, timeout: float = 5.0) -> None:
        """Ask the sim to stop (SIGTERM), then kill it if it does not. A stopped one
        (SIGSTOP, Ctrl-Z in its terminal) is continued after the SIGTERM, so that it ends
        on the request at once instead of being killed after ``timeout``."""
        if self._proc.poll() is None:
            self._proc.terminate()
            with contextlib.suppress(ProcessLookupError):
                os.kill(self._proc.pid, signal.SIGCONT)
            try:
                self._proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                with contextlib.suppress(subprocess.TimeoutExpired):
                    self._proc.wait(timeout)

    def __enter__(self) -> SimProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
