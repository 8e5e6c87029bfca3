"""``python -m sim._forkserver FD``: start simulators by forking a process that is warm.

Why: a cold ``python -m sim`` takes a while before it is ready (numba's import
and its first load of the cached kernels), and a process that starts many (a
test suite, Monte-Carlo seeds) would pay that each time. This server does it
once, then forks a child per simulator, ready almost at once (figures:
docs/performance.md, "Many flights at once"). It opens no zenoh session and
starts no thread of its own before it forks: each child opens its own, as a
cold simulator would.

Protocol, over the socket inherited as FD (``gcs.app._simfork`` is the client):
each request is one message carrying a JSON object ``{"argv": [...], "cwd":
..., "env": {...}}`` (length-prefixed, 4 bytes big-endian) and three file
descriptors by SCM_RIGHTS: the child's stdout, its stderr, and a status socket
on which the server writes ``pid N`` once forked and ``exit CODE`` once
reaped. The server exits when the client's end closes; its children then get
SIGTERM (PR_SET_PDEATHSIG), as a cold simulator does when its GCS dies.
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import signal
import socket
import struct
import sys

from gcs.common import die_with_parent

__all__ = ["serve", "warm_up"]

_HEADER = struct.Struct(">I")
_MAX_REQUEST = 1 << 20
"""Largest request accepted, bytes (argv, cwd and the environment)."""
_REAP_S = 0.1
"""How often finished children are reaped and their exit told, s."""


def warm_up() -> None:
    """Import the simulator and load its kernels: one chunk of the default team's flight.

    A failure here only costs the children the work (each then loads what it needs).
    """
    import numpy as np

    import sim.__main__  # noqa: F401  (the whole host: MAVLink, zenoh's module, configs)
    from gcs.common import shipped_config
    from gcs.config import load_team
    from sim._config import load_world_config
    from sim._host import CHUNK_S
    from sim._ready_team import DEFAULT_AUTOPILOT_CONFIG, DEFAULT_WORLD_CONFIG, build_team
    from sim._team_layout import team_layout
    from vehicles import load_autopilot_config

    team = load_team(shipped_config("bebop_square.yaml"))
    world_config = load_world_config(DEFAULT_WORLD_CONFIG)
    world, autopilot = build_team(
        team_layout(team, ground_z_ned=world_config.ground.z_ned),
        payload_mass=team.config.payload.mass, rng=np.random.default_rng(0),
        airframe=team.config.airframe, world_config=world_config,
        autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    world.run(autopilot, CHUNK_S)


def _recv_exact(sock: socket.socket, n: int, fds: list[int]) -> bytes | None:
    """``n`` bytes (None at end of stream), collecting any descriptors passed with them."""
    data = b""
    while len(data) < n:
        chunk, new_fds, _flags, _addr = socket.recv_fds(sock, n - len(data), 8)
        fds.extend(new_fds)
        if not chunk:
            return None
        data += chunk
    return data


def _child(request: dict[str, object], out: int, err: int,
           inherited: list[socket.socket]) -> None:
    """In the forked child: become ``python -m sim ARGV`` in the client's directory and
    environment, its output on the client's pipes; never returns."""
    code = 1
    try:
        for sock in inherited:  # the server's: the control socket, the other children's
            sock.close()
        die_with_parent()  # the server: it exits with its client
        for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGCHLD):
            signal.signal(signum, signal.SIG_DFL)
        os.dup2(out, 1)
        os.dup2(err, 2)
        os.close(out)
        os.close(err)
        sys.stdout = open(1, "w", buffering=1, encoding="utf-8", closefd=False)  # noqa: SIM115
        sys.stderr = open(2, "w", buffering=1, encoding="utf-8", closefd=False)  # noqa: SIM115
        os.chdir(str(request["cwd"]))
        env = request["env"]
        assert isinstance(env, dict)
        os.environ.clear()
        os.environ.update({str(k): str(v) for k, v in env.items()})
        given = request["argv"]
        assert isinstance(given, list)
        argv = [str(a) for a in given]
        sys.argv = ["python -m sim", *argv]
        from sim.__main__ import main

        code = main(argv)
    except SystemExit as exc:  # argparse
        code = exc.code if isinstance(exc.code, int) else 2
    except BaseException as exc:  # the child must end here, whatever it is
        with contextlib.suppress(Exception):
            print(f"sim: error: {type(exc).__name__}: {exc}", file=sys.stderr, flush=True)
    finally:
        with contextlib.suppress(Exception):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code)


def serve(ctl: socket.socket) -> None:
    """Fork a simulator per request on ``ctl`` until its other end closes."""
    status: dict[int, socket.socket] = {}  # child pid -> its status socket
    try:
        while True:
            readable, _, _ = select.select([ctl], [], [], _REAP_S)
            _reap(status)
            if not readable:
                continue
            fds: list[int] = []
            header = _recv_exact(ctl, _HEADER.size, fds)
            if header is None:
                return
            (size,) = _HEADER.unpack(header)
            body = _recv_exact(ctl, size, fds) if size <= _MAX_REQUEST else None
            if body is None or len(fds) != 3:
                for fd in fds:
                    os.close(fd)
                return  # not our client: stop rather than guess
            out, err, reply = fds
            answer = socket.socket(fileno=reply)
            try:
                request = json.loads(body)
            except ValueError:
                request = None
            if not isinstance(request, dict) or not {"argv", "cwd", "env"} <= set(request):
                os.close(out)
                os.close(err)
                with contextlib.suppress(OSError):
                    answer.sendall(b"exit 2\n")
                answer.close()
                continue
            pid = os.fork()
            if pid == 0:
                _child(request, out, err, [ctl, answer, *status.values()])
            os.close(out)
            os.close(err)
            status[pid] = answer
            try:
                answer.sendall(f"pid {pid}\n".encode())
            except OSError:  # the client gave this one up before it was forked: stop it
                os.kill(pid, signal.SIGTERM)
    finally:
        for answer in status.values():
            answer.close()


def _reap(status: dict[int, socket.socket]) -> None:
    """Tell each client whose child ended how it ended."""
    while status:
        try:
            pid, wait_status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        answer = status.pop(pid, None)
        if answer is None:
            continue
        code = os.waitstatus_to_exitcode(wait_status)
        with contextlib.suppress(OSError):
            answer.sendall(f"exit {code}\n".encode())
        answer.close()


def main(argv: list[str]) -> int:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a terminal's Ctrl-C is for the client
    ctl = socket.socket(fileno=int(argv[0]))
    with contextlib.suppress(Exception):
        warm_up()
    serve(ctl)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
