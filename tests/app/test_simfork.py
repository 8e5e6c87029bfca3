"""Simulators forked from a warm server (gcs.app._simfork, sim._forkserver).

The flight a forked simulator gives is the one a cold ``python -m sim`` gives, to the last
digit: ``tests/integration/test_fly_seeds.py`` compares a seed flown by ``gcs fly`` (a cold
simulator) with the same seed from ``fly_seeds`` (forked).
"""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from gcs.app import SimProcess, SimStartError, _simfork, free_tcp_port
from gcs.app._simfork import ForkedSim
from tests.support.paths import ROOT


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


def _endpoint() -> str:
    return f"tcp/127.0.0.1:{free_tcp_port()}"


def test_a_forked_simulator_starts_in_the_callers_directory_and_stops_when_closed(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Started twice: the second is ready at once; each runs where the caller stands
    (a config path relative to the caller's directory at the start) and is gone once
    closed."""
    monkeypatch.chdir(ROOT / "configs")
    with SimProcess("bebop_square.yaml", endpoint=_endpoint(), speed="max",
                    lockstep=True) as first:
        assert isinstance(first._proc, ForkedSim)
        assert first.ready_line.startswith("sim ready: fleet default, 4 vehicles")
    assert not _alive(first._proc.pid) and first._proc.returncode == 0
    monkeypatch.chdir(ROOT)
    start = time.monotonic()
    with SimProcess("configs/bebop_triangle.yaml", endpoint=_endpoint(), speed="max",
                    lockstep=True) as second:
        ready_s = time.monotonic() - start
        assert second.ready_line.startswith("sim ready: fleet default, 3 vehicles")
        pid = second._proc.pid
        assert pid != first._proc.pid and _alive(pid)
    assert not _alive(pid)
    print(f"forked simulator ready in {ready_s:.3f} s")


def test_a_bad_team_is_the_one_line_a_cold_start_gives(tmp_path: Path) -> None:
    """A team file whose airframe is not where it says: the forked simulator ends before
    it is ready with the same one-line error as a fresh ``python -m sim``."""
    bad = tmp_path / "moved.yaml"
    bad.write_text((ROOT / "configs/bebop_square.yaml").read_text())
    said = []
    for fork_server in (True, False):
        with pytest.raises(SimStartError) as caught:
            SimProcess(bad, endpoint=_endpoint(), speed="max", lockstep=True,
                       fork_server=fork_server)
        said.append(str(caught.value))
    assert said[0] == said[1], said
    assert said[0] == (f"the simulator exited before it was ready: sim: error: {bad}: "
                       f"airframe: file not found: airframes/bebop2.yaml"), said[0]


def test_without_the_fork_server_a_simulator_is_a_fresh_process(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("GCS_SIM_FORK", "0")
    with SimProcess(ROOT / "configs/bebop_square.yaml", endpoint=_endpoint(),
                    speed="max", lockstep=True) as sim:
        assert isinstance(sim._proc, subprocess.Popen)
    monkeypatch.delenv("GCS_SIM_FORK")
    with SimProcess(ROOT / "configs/bebop_square.yaml", endpoint=_endpoint(), speed="max",
                    lockstep=True, fork_server=False) as sim:
        assert isinstance(sim._proc, subprocess.Popen)


KILLED = textwrap.dedent("""
    import os, signal, sys
    from gcs.app import SimProcess, free_tcp_port
    sim = SimProcess(sys.argv[1], endpoint=f"tcp/127.0.0.1:{free_tcp_port()}", speed="max",
                     lockstep=True)
    print(sim._proc._server.pid, sim._proc.pid, flush=True)
    os.kill(os.getpid(), signal.SIGKILL)
""")


def test_a_gcs_killed_leaves_neither_its_server_nor_its_simulator() -> None:
    """As a cold simulator dies with its GCS (PR_SET_PDEATHSIG), a forked one does: the
    server ends when its client's socket closes, and its children with it."""
    done = subprocess.run([sys.executable, "-c", KILLED,
                           str(ROOT / "configs/bebop_square.yaml")],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == -9, done.stderr
    server, sim = map(int, done.stdout.split())
    assert server != sim
    deadline = time.monotonic() + 10.0
    while (_alive(server) or _alive(sim)) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(server), f"the fork server {server} outlived its GCS"
    assert not _alive(sim), f"the simulator {sim} outlived its GCS"


def test_the_server_is_stopped_when_the_process_exits() -> None:
    script = textwrap.dedent("""
        import sys
        from gcs.app import SimProcess, free_tcp_port
        with SimProcess(sys.argv[1], endpoint=f"tcp/127.0.0.1:{free_tcp_port()}",
                        speed="max", lockstep=True) as sim:
            assert type(sim._proc).__name__ == "ForkedSim"
            print(sim._proc._server.pid, flush=True)
    """)
    done = subprocess.run([sys.executable, "-c", script,
                           str(ROOT / "configs/bebop_square.yaml")],
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    assert not _alive(int(done.stdout)), "the fork server is left after its process exited"


def test_a_simulator_given_up_before_it_was_forked_is_stopped_once_it_is(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Closed while the server still warms up, a simulator cannot be signalled yet: the
    client gives it up, and the server, unable to tell it the pid, stops it at once."""
    monkeypatch.setattr(_simfork, "_STOP_WAIT_S", 0.0)
    _simfork._SERVER.stop()  # a fresh server: it warms up for about a second
    config = str(ROOT / "configs/bebop_square.yaml")
    given_up = _simfork.fork_sim(["--config", config, "--listen", _endpoint(), "--speed",
                                  "max", "--lockstep"])
    given_up.terminate()
    assert given_up.returncode == -signal.SIGTERM and given_up._child is None
    server = given_up._server.pid
    # requests are served in order: once the next one is up, the first was forked
    with SimProcess(config, endpoint=_endpoint(), speed="max", lockstep=True) as next_one:
        children = set()
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline:
            children = {int(p) for p in subprocess.run(
                ["pgrep", "-P", str(server)], capture_output=True, text=True,
                check=False).stdout.split()}
            if children == {next_one._proc.pid}:
                break
            time.sleep(0.05)
        assert children == {next_one._proc.pid}, (children, next_one._proc.pid)
