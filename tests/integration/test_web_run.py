"""``gcs run`` against a ``gcs sim`` started apart, as an operator runs them (two processes).

The GCS reaches the simulated team only through its config's zenoh settings,
exactly as it would reach a sim on another machine; the page is read by a
plain websocket client that decodes what viser sends (the status table).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import viser
import zstandard
from websockets.sync.client import connect

from gcs.app import free_tcp_port
from gcs.cli import build_parser
from tests.support.paths import ROOT

CONFIG = ROOT / "configs" / "bebop_square.yaml"


def team_file(directory: Path, endpoint: str) -> Path:
    """The paper's team, its GCS joining the sim at ``endpoint`` (the config's links)."""
    text = CONFIG.read_text().replace("airframe: airframes/",
                                      f"airframe: {CONFIG.parent / 'airframes'}/")
    path = directory / "team.yaml"
    path.write_text(f"{text}\ngcs:\n  zenoh: {{mode: peer, connect: [{endpoint}]}}\n")
    return path


class Process:
    """A child process whose output lines are collected as they come."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "gcs", *args], cwd=ROOT,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     env={**os.environ, "PYTHONUNBUFFERED": "1"})
        self.out: list[str] = []
        self.err: list[str] = []
        for stream, sink in ((self.proc.stdout, self.out), (self.proc.stderr, self.err)):
            threading.Thread(target=self._pump, args=(stream, sink), daemon=True).start()

    @staticmethod
    def _pump(stream, sink: list[str]) -> None:  # type: ignore[no-untyped-def]
        for line in stream:
            sink.append(line)

    def wait_for(self, pattern: str, timeout: float) -> re.Match[str]:
        """The first output line matching ``pattern``."""
        deadline = time.monotonic() + timeout
        while True:
            for line in list(self.out):
                if m := re.search(pattern, line):
                    return m
            assert self.proc.poll() is None, f"exited: {''.join(self.err[-8:])}"
            assert time.monotonic() < deadline, f"no {pattern!r} in {self.out}"
            time.sleep(0.05)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)


@pytest.fixture
def sim_endpoint() -> Iterator[str]:
    """A ``gcs sim`` of the paper's team at 1x on a free loopback port."""
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    sim = Process("sim", "--config", str(CONFIG), "--listen", endpoint, "--speed", "1")
    try:
        sim.wait_for(r"^sim ready", 60.0)
        yield endpoint
    finally:
        sim.stop()


def listeners(port: int) -> set[str]:
    """Local addresses (hex, as the kernel lists them) listening on TCP ``port``."""
    found = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        with open(table) as f:
            for row in f.readlines()[1:]:
                local, state = row.split()[1], row.split()[3]
                address, hex_port = local.rsplit(":", 1)
                if state == "0A" and int(hex_port, 16) == port:  # 0A: LISTEN
                    found.add(address)
    return found


def page_messages(port: int, until: Callable[[bytes], bool], timeout: float) -> bytes:
    """What the page sent a viewer (viser's msgpack, decompressed) until ``until`` holds."""
    seen = b""
    unzip = zstandard.ZstdDecompressor()
    deadline = time.monotonic() + timeout
    with connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"],
                 max_size=None) as ws:
        while not until(seen):
            assert time.monotonic() < deadline, f"the page never showed it: {seen[-2000:]!r}"
            try:
                raw = ws.recv(timeout=0.5)
            except TimeoutError:
                continue
            assert isinstance(raw, bytes)
            size, packed = (int.from_bytes(raw[k:k + 8], "little") for k in (0, 8))
            seen += unzip.decompress(raw[16:16 + packed], max_output_size=size)
    return seen


def vehicle_rows(seen: bytes) -> dict[int, str]:
    """The latest status row of each vehicle in what the page sent, as text."""
    rows = {}
    for vid, row in re.findall(rb'data-gcs="vehicle-(\d+)">(.*?)</tr>', seen):
        rows[int(vid)] = re.sub(r"<[^>]+>", " ", row.decode())
    return rows


def test_a_page_is_served_on_this_machine_only_unless_another_host_is_asked() -> None:
    parser = build_parser()
    for command in (["run", "--config", "team.yaml"], ["demo"]):
        assert parser.parse_args(command).host == "127.0.0.1"
        assert parser.parse_args([*command, "--host", "0.0.0.0"]).host == "0.0.0.0"


def test_gcs_run_flies_a_gcs_sim_and_stops_on_sigterm(sim_endpoint: str,
                                                      tmp_path: Path) -> None:
    port = free_tcp_port()
    gcs = Process("run", "--config", str(team_file(tmp_path, sim_endpoint)),
                  "--port", str(port), "--no-gamepad")
    try:
        url = gcs.wait_for(r"GCS page: (http://\S+)", 60.0).group(1)
        assert url == f"http://127.0.0.1:{port}"
        assert listeners(port) == {"0100007F"}  # 127.0.0.1 only, no other interface
        with urllib.request.urlopen(url, timeout=10) as page:
            assert page.status == 200 and b"<html" in page.read().lower()
        # every vehicle of the sim in the status table: heard (ok), disarmed on the ground
        def all_heard(seen: bytes) -> bool:
            rows = vehicle_rows(seen)
            return sorted(rows) == [1, 2, 3, 4] and all(
                " ok " in row and "DISARMED" in row for row in rows.values())

        page_messages(port, until=all_heard, timeout=20.0)
        gcs.proc.send_signal(signal.SIGTERM)
        assert gcs.proc.wait(15) == 0, "".join(gcs.err[-10:])
        assert any("stopping" in line for line in gcs.out)
        assert not listeners(port)
    finally:
        gcs.stop()

