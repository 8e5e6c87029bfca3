"""``python -m sim`` as a parent process sees it: ready line, lockstep, clock, exits.

The lockstep test plays the GCS's part by hand on a real zenoh session: it
reads the clock and the truth samples and sends clock acks.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import selectors
import signal
import socket
import subprocess
import sys
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import zenoh
from pymavlink.dialects.v20 import ardupilotmega as mavlink2

from gcs.app import SimProcess, SimStartError, _simprocess, free_tcp_port
from gcs.common import to_mapping
from gcs.config import load_team
from gcs.testing import signed_connection, team_key
from gcs.transport import ZenohSettings, open_session
from gcs.wire import Sealer, SimTruth, Unsealer, decode_clock, encode_time, keys
from sim.__main__ import main as sim_main
from tests.support.paths import ROOT
from tests.support.ports import free_udp_ports

CONFIG = ROOT / "configs" / "bebop_square.yaml"
CHUNK = 1.0 / 128.0


def sim_command(*args: str) -> list[str]:
    return [sys.executable, "-m", "sim", *args]


@contextlib.contextmanager
def running(*args: str) -> Iterator[tuple[subprocess.Popen[str], str]]:
    """Start the host, wait for its ready line; the process never outlives the test."""
    proc = subprocess.Popen(sim_command(*args), cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        line = first_line(proc)
        if not line.startswith("sim ready: "):
            proc.kill()
            _, err = proc.communicate(timeout=10)
            pytest.fail(f"no ready line (got {line!r}): {err}")
        yield proc, line
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate(timeout=10)


def first_line(proc: subprocess.Popen[str], timeout_s: float = 120.0) -> str:
    """The process's first line of output, or '' if none comes in time (first runs compile
    the simulator's kernels)."""
    assert proc.stdout is not None
    with selectors.DefaultSelector() as selector:
        selector.register(proc.stdout, selectors.EVENT_READ)
        if not selector.select(timeout_s):
            return ""
    return proc.stdout.readline().strip()


def eventually(condition: Callable[[], bool], what: str, timeout_s: float = 5.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


def test_bad_config_is_one_line_and_exit_status_2(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    text = CONFIG.read_text().replace("airframes/bebop2.yaml",
                                      str(ROOT / "configs" / "airframes" / "bebop2.yaml"))
    bad = tmp_path / "team.yaml"
    bad.write_text(text.replace("mass: 0.4   ", "mass: -0.4  "))
    result = subprocess.run(sim_command("--config", str(bad)), cwd=ROOT, capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == 2 and result.stdout == ""
    assert result.stderr.startswith("sim: error: ") and result.stderr.count("\n") == 1
    assert "payload.mass" in result.stderr
    for args, named in ((("--config", str(tmp_path / "missing.yaml")), "missing.yaml"),
                        (("--config", str(CONFIG), "--listen", "tcp-127.0.0.1"), "listen"),
                        (("--config", str(CONFIG), "--duration", "-1"), "duration"),
                        (("--config", str(CONFIG), "--gusts", "40"), "--gusts"),
                        (("--config", str(CONFIG), "--gusts", "nan"), "--gusts"),
                        (("--config", str(CONFIG), "--team-json", "{"), "--team-json"),
                        (("--config", str(CONFIG), "--team-json", "[1]"), "a JSON object"),
                        (("--config", str(CONFIG), "--team-json", "null"), "a JSON object"),
                        (("--config", str(CONFIG), "--team-json", json.dumps(
                            {**to_mapping(load_team(CONFIG).config), "payload": {"mass": 0.2}})),
                         "payload.rope_length")):
        assert sim_main(list(args)) == 2
        out, err = capsys.readouterr()
        assert out == "" and err.startswith("sim: error: ") and err.count("\n") == 1, err
        assert named in err


def test_lockstep_host_waits_for_acks_and_stops_cleanly_on_sigint() -> None:
    fleet = f"simcli-{uuid.uuid4().hex[:8]}"
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    with running("--config", str(CONFIG), "--listen", endpoint, "--fleet", fleet,
                 "--lockstep", "--seed", "3") as (proc, ready):
        err = lockstep_as_a_gcs(proc, ready, fleet, endpoint)
    assert "sim: stopped at t = 1.250 s" in err
    assert "ignored clock ack" in err


def lockstep_as_a_gcs(proc: subprocess.Popen[str], ready: str, fleet: str,
                      endpoint: str) -> str:
    """Play the GCS's part against a lockstep host; returns its stderr after SIGINT."""
    assert ready == (f"sim ready: fleet {fleet}, 4 vehicles, zenoh listen {endpoint}, "
                     "speed max, lockstep 0.25 s")
    session = open_session(ZenohSettings(connect=(endpoint,)))
    clock: list[tuple[float, float]] = []
    announced: list[dict[int, int]] = []
    truth_count: list[int | None] = []
    truth: list[SimTruth] = []

    open_clock = Unsealer(team_key(), keys.clock(fleet)).open  # the host seals its keys
    open_truth = Unsealer(team_key(), keys.sim(fleet, "truth")).open

    def on_clock(s: zenoh.Sample) -> None:
        sample = decode_clock(open_clock(s.payload.to_bytes()))
        clock.append((time.monotonic(), sample.t))
        announced.append(dict(sample.sent))
        truth_count.append(sample.truth)

    subs = [session.declare_subscriber(keys.clock(fleet), on_clock),
            session.declare_subscriber(keys.sim(fleet, "truth"), lambda s: truth.append(
                SimTruth.from_bytes(open_truth(s.payload.to_bytes()))))]
    try:
        # Without an ack the host stands at its first chunk (nothing runs before a GCS
        # acks, so what a GCS sees does not depend on when it joined), and keeps
        # repeating its clock so that a late GCS still learns where it is.
        # (not "n in the last half second": beside two CPU hogs a waiting host's republish
        # came 0-8 times a half second, in bursts, with or without zenoh's express)
        eventually(lambda: len(clock) >= 3 and clock[-1][0] - clock[0][0] > 0.5,
                   "clock samples while waiting")
        assert {t for _, t in clock} == {CHUNK}, clock
        # each sample says how many truth samples, and payloads of every vehicle, the host
        # has published so far
        assert set(announced[-1]) == {1, 2, 3, 4} and truth_count[-1] == len(truth) == 0
        before = announced[-1]
        ack = session.declare_publisher(keys.clock_ack(fleet))
        ack.put(b"junk")  # ignored (logged), not fatal
        ack.put(encode_time(1.0))  # a stranger's: not sealed, ignored too
        time.sleep(0.3)
        assert max(t for _, t in clock) == pytest.approx(CHUNK)
        ack.put(Sealer(team_key(), keys.clock_ack(fleet)).seal(encode_time(1.0)))
        eventually(lambda: clock[-1][1] == pytest.approx(1.25), "the clock to reach 1.25 s")
        time.sleep(0.3)
        assert max(t for _, t in clock) == pytest.approx(1.25)  # and not one chunk further
        assert all(announced[-1][s] > n for s, n in before.items())  # telemetry went out
        steps = sorted({t for _, t in clock if t >= CHUNK - 1e-9})  # from the first wait on
        # the sim advances in whole chunks; clock samples are latest-wins (some may be
        # dropped under load), and it never ran past the ack (checked above)
        gaps = [(b - a) / CHUNK for a, b in itertools.pairwise(steps)]
        bad = [g for g in gaps if not (g == pytest.approx(round(g)) and round(g) >= 1)]
        assert not bad, (bad, steps[:3], steps[-3:])
        # 20 Hz of sim time from the first chunk to 1.25 s, none dropped in lockstep, each
        # counted by the clock sample that follows it
        assert [round(s.t * 20) for s in truth] == list(range(len(truth)))
        assert len(truth) == 26 and truth_count[-1] == 26  # t = 0 (first chunk) to 1.25 s
        ack.undeclare()
    finally:
        for sub in subs:
            sub.undeclare()
        session.close()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=10)
    assert proc.returncode == 0, err
    return err


def test_duration_runs_as_fast_as_possible_and_exits_by_itself() -> None:
    start_wall = time.monotonic()
    with running("--config", str(CONFIG), "--listen", f"tcp/127.0.0.1:{free_tcp_port()}",
                 "--fleet", f"simcli-{uuid.uuid4().hex[:8]}", "--speed", "max", "--duration",
                 "3", "--gusts", "0.5") as (proc, ready):
        assert ready.endswith("speed max, gusts 0.5 m/s")
        _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert "sim: stopped at t = 3.000 s" in err
    assert time.monotonic() - start_wall < 30.0


def test_the_help_puts_the_first_vehicle_on_the_base_port() -> None:
    """As the ready line below shows: the first vehicle on P, the second on P+1 (the help
    said vehicle k on P+k, which puts vehicle 1 on P+1)."""
    out = subprocess.run(sim_command("--help"), cwd=ROOT, capture_output=True, text=True,
                         timeout=60, check=True).stdout
    text = " ".join(out.split())
    assert "P+k" not in text
    assert "first vehicle (on P); the others follow in team order on P+1, P+2" in text


def test_gcs_sim_hosts_the_team_with_sitl_style_udp_ports_and_stops_on_sigint() -> None:
    """``gcs sim`` hands its options to the simulator: a pymavlink client on vehicle 2's UDP
    port gets that vehicle's HEARTBEAT and an acknowledged command, as from a SITL."""
    base = free_udp_ports(4)
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    proc = subprocess.Popen([sys.executable, "-m", "gcs", "sim", "--config", str(CONFIG),
                             "--listen", endpoint, "--fleet", f"gcssim-{uuid.uuid4().hex[:8]}",
                             "--udp", "--udp-base-port", str(base), "--udp-gcs-port", "0"],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        ready = first_line(proc)
        assert ready.startswith("sim ready: ") and f"2=127.0.0.1:{base + 1}" in ready, ready
        client = signed_connection(f"udpout:127.0.0.1:{base + 1}", source_system=200,
                                   source_component=190)
        try:
            deadline = time.monotonic() + 10.0
            heartbeat = ack = None
            while (heartbeat is None or ack is None) and time.monotonic() < deadline:
                client.mav.heartbeat_send(6, 8, 0, 0, 0)  # a GCS: the vehicle learns our port
                client.mav.command_long_send(2, 1, mavlink2.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                                             mavlink2.MAVLINK_MSG_ID_SYS_STATUS, 200_000,
                                             0, 0, 0, 0, 0)
                msg = client.recv_match(type=["HEARTBEAT", "COMMAND_ACK"], blocking=True,
                                        timeout=0.5)
                if msg is not None and msg.get_srcSystem() == 2:
                    if msg.get_type() == "HEARTBEAT":
                        heartbeat = msg
                    else:
                        ack = msg
        finally:
            client.close()
        assert heartbeat is not None and heartbeat.type == mavlink2.MAV_TYPE_QUADROTOR
        assert ack is not None and ack.result == mavlink2.MAV_RESULT_ACCEPTED
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=15)
        assert proc.returncode == 0, err
        assert "sim: stopped at t = " in err
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate(timeout=10)


def test_a_slow_start_is_said_not_silent() -> None:
    """The first ``gcs demo`` sat 68 s silent while the kernels compiled: it looked hung.
    A simulator that is not ready yet is now told every few seconds (here one that never
    becomes ready: a shell that sleeps, in the simulator's place)."""
    said: list[str] = []
    with pytest.raises(SimStartError, match=r"was not ready after [67] s \(idle"):
        SimProcess(CONFIG, endpoint=f"tcp/127.0.0.1:{free_tcp_port()}", ready_timeout=6.0,
                   wrap=lambda *cmd: ["sh", "-c", "sleep 30"], progress=said.append)
    assert said and said[0].startswith("the simulator is still starting (5 s, 0 s of CPU): "
                                       "its first start compiles its kernels"), said


def test_a_simulator_that_works_past_its_timeout_is_waited_for_and_a_runaway_is_not() -> None:
    """A first start compiles its kernels: about 18 s of CPU, over 60 s of wall time on a
    machine where other processes take most of the cores (seen beside two CPU hogs). A
    starting simulator whose CPU time grows is waited for, up to five times its timeout;
    one that spins without ever being ready is given up at that ceiling."""
    # busy for 3 s of wall time, then ready: past its 2 s timeout, and within the 10 s
    # ceiling however little of a core it gets (2.5 s of CPU were not done in 10 s beside
    # two CPU hogs)
    works = ("import time\nt = time.monotonic()\nwhile time.monotonic() - t < 3.0: pass\n"
             "print('sim ready: a stand-in', flush=True)\ntime.sleep(30)")
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    with SimProcess(CONFIG, endpoint=endpoint, ready_timeout=2.0,
                    wrap=lambda *cmd: [sys.executable, "-c", works]) as sim:
        assert sim.ready_line == "sim ready: a stand-in"

    start = time.monotonic()
    with pytest.raises(SimStartError, match=r"was not ready after \d+ s \(still busy"):
        SimProcess(CONFIG, endpoint=endpoint, ready_timeout=0.5,
                   wrap=lambda *cmd: [sys.executable, "-c", "while True: pass"])
    assert time.monotonic() - start < 10.0


def test_a_simulator_whose_port_was_taken_before_it_bound_it_starts_on_another(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The race of a port picked free and bound by another process before the simulator
    (seen with flights side by side on a loaded machine): ``on_free_port`` picks another;
    given one attempt it says what happened."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        picks = itertools.chain([port], iter(free_tcp_port, None))
        monkeypatch.setattr(_simprocess, "free_tcp_port", lambda: next(picks))
        with SimProcess.on_free_port(CONFIG, speed="max", lockstep=True) as sim:
            assert sim.alive() and sim.endpoint != f"tcp/127.0.0.1:{port}", sim.endpoint
        picks = itertools.chain([port], iter(free_tcp_port, None))
        with pytest.raises(SimStartError, match=f"127.0.0.1:{port}.*Address already in use"):
            SimProcess.on_free_port(CONFIG, speed="max", lockstep=True, attempts=1)
