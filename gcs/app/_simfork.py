"""Simulators forked from a warm server: ready in tens of milliseconds, not two seconds.

A cold ``python -m sim`` spends about a second of CPU on numba's import and its
first load of the cached kernels before it is ready. A process that starts many
simulators (``SimTeam`` in a test suite, the seeds of a Monte-Carlo run in one
worker) starts one server (:mod:`sim._forkserver`) with its first simulator and
forks every simulator from it. Each child runs ``python -m sim``'s ``main`` with
this process's working directory and environment at the time of the start, so
it is the simulator a cold start gives, sooner. ``GCS_SIM_FORK=0`` turns it off.

The server lives as long as this process (it exits when its socket closes) and
is stopped at exit; its children die with it, as a cold simulator dies with
its GCS.
"""

from __future__ import annotations

import atexit
import contextlib
import json
import os
import select
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
from typing import IO

__all__ = ["ForkedSim", "fork_server_enabled", "fork_sim"]

_HEADER = struct.Struct(">I")
_STOP_WAIT_S = 5.0
"""How long the process's exit waits for the server and its children to end, s."""


def fork_server_enabled() -> bool:
    """Whether simulators may be forked from a warm server (``GCS_SIM_FORK`` is not 0)."""
    return os.environ.get("GCS_SIM_FORK", "1").strip() != "0"


class ForkedSim:
    """A simulator the server forked: what :class:`gcs.app.SimProcess` uses of a
    :class:`subprocess.Popen` (``pid``, ``poll``, ``wait``, ``terminate``, ``kill``)."""

    def __init__(self, status: socket.socket, stdout: IO[str], stderr: IO[str],
                 server: subprocess.Popen[bytes]) -> None:
        self.stdout = stdout
        self.stderr = stderr
        self.returncode: int | None = None
        self._status = status
        self._server = server
        self._child: int | None = None
        self._buffer = b""
        self._lock = threading.Lock()

    @property
    def pid(self) -> int:
        """The simulator's pid; the server's while it has not forked it yet (warming up)."""
        self.poll()
        return self._child if self._child is not None else self._server.pid

    def _read(self, timeout: float) -> None:
        """Take what the server said of this child within ``timeout`` s (the wait holds
        no lock: another thread's poll is never kept waiting by it)."""
        if self.returncode is not None:
            return
        try:
            readable, _, _ = select.select([self._status], [], [], max(0.0, timeout))
        except (OSError, ValueError):  # closed by another thread meanwhile
            return
        if not readable:
            return
        with self._lock:
            if self.returncode is not None:
                return
            try:
                data = self._status.recv(256, socket.MSG_DONTWAIT)
            except BlockingIOError:  # another thread took it
                return
            except OSError:
                data = b""
            if not data:  # the server is gone: so is the child (it dies with the server)
                self.returncode = -signal.SIGKILL
                self._status.close()
                return
            self._buffer += data
            *lines, self._buffer = self._buffer.split(b"\n")
            for line in lines:
                word, _, value = line.decode("ascii", "replace").partition(" ")
                if word == "pid" and value.isdigit():
                    self._child = int(value)
                elif word == "exit":
                    self.returncode = int(value) if value.lstrip("-").isdigit() else 1
                    self._status.close()
                    return

    def poll(self) -> int | None:
        self._read(0.0)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        deadline = None if timeout is None else time.monotonic() + timeout
        while self.returncode is None:
            left = 1.0 if deadline is None else deadline - time.monotonic()
            if left <= 0:
                raise subprocess.TimeoutExpired("python -m sim (forked)", timeout or 0.0)
            self._read(min(left, 1.0))
        return self.returncode

    def send_signal(self, signum: int) -> None:
        """Signal the simulator; one not forked yet is waited for first (the server is
        warming up), and given up after a few seconds: the server then stops it as soon
        as it forks it (it cannot tell it its pid), so a stop is never lost."""
        deadline = time.monotonic() + _STOP_WAIT_S
        while self._child is None and self.poll() is None and time.monotonic() < deadline:
            self._read(0.1)
        with self._lock:
            if self.returncode is None and self._child is None:
                self.returncode = -signum
                self._status.close()
                return
        if self.poll() is None and self._child is not None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(self._child, signum)

    def terminate(self) -> None:
        self.send_signal(signal.SIGTERM)

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)


class _Server:
    """This process's fork server, started with the first simulator forked."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._proc: subprocess.Popen[bytes] | None = None
        self._ctl: socket.socket | None = None
        self._owner = os.getpid()

    def _running(self) -> tuple[subprocess.Popen[bytes], socket.socket]:
        if self._owner != os.getpid():  # a forked copy of the process: the server is not ours
            self._proc, self._ctl, self._owner = None, None, os.getpid()
        if self._proc is None or self._ctl is None or self._proc.poll() is not None:
            self._stop_locked()
            ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
            try:
                self._proc = subprocess.Popen(
                    [sys.executable, "-m", "sim._forkserver", str(theirs.fileno())],
                    pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL,
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            finally:
                theirs.close()
            self._ctl = ours
        return self._proc, self._ctl

    def fork(self, argv: list[str]) -> ForkedSim:
        """Ask the server for ``python -m sim ARGV``; OSError if it cannot be asked."""
        body = json.dumps({"argv": argv, "cwd": os.getcwd(), "env": dict(os.environ)}).encode()
        out_r, out_w = os.pipe()
        err_r, err_w = os.pipe()
        status, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            with self._lock:
                proc, ctl = self._running()
                try:
                    socket.send_fds(ctl, [_HEADER.pack(len(body)) + body],
                                    [out_w, err_w, theirs.fileno()])
                except OSError:
                    self._stop_locked()
                    raise
        except BaseException:
            for fd in (out_r, err_r):
                os.close(fd)
            status.close()
            raise
        finally:
            os.close(out_w)
            os.close(err_w)
            theirs.close()
        return ForkedSim(status, open(out_r, encoding="utf-8", errors="replace"),
                         open(err_r, encoding="utf-8", errors="replace"), proc)

    def _stop_locked(self) -> None:
        if self._ctl is not None:
            self._ctl.close()  # the server exits at end of stream; its children die with it
            self._ctl = None
        if self._proc is not None:
            try:
                self._proc.wait(_STOP_WAIT_S)
            except subprocess.TimeoutExpired:
                self._proc.kill()
                self._proc.wait()
            self._proc = None

    def stop(self) -> None:
        with self._lock:
            if self._owner == os.getpid():
                self._stop_locked()


_SERVER = _Server()
atexit.register(_SERVER.stop)


def fork_sim(argv: list[str]) -> ForkedSim:
    """``python -m sim ARGV`` forked from this process's warm server (started on first use);
    OSError where the server cannot be reached (the caller then starts a cold one)."""
    return _SERVER.fork(argv)
