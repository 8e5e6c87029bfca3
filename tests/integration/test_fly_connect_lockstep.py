"""``gcs fly --connect`` to a simulator started elsewhere: in lockstep with one started with
``--lockstep`` on another host (a network namespace), the same flight to the last digit as
``gcs fly`` starting its own; what cannot be sound is refused at once with the reason."""

from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from gcs.app import GcsApp, SimProcess, free_tcp_port
from gcs.app._simjoin import free_pace
from gcs.common import ConfigError
from gcs.config import load_team
from gcs.loop import ClockStoppedError
from gcs.testing import Host, Metrics
from gcs.transport import ZenohSettings
from tests.support.commands import run_gcs
from tests.support.paths import SHORT
from tests.support.paths import SQUARE as CONFIG

TEAM = load_team(CONFIG)


def _fly(*extra: str) -> tuple[subprocess.CompletedProcess[str], float]:
    """``gcs fly --json`` of the short flight; the run and its wall time, s."""
    start = time.monotonic()
    run = run_gcs("fly", "--config", CONFIG, "--scenario", SHORT, "--json", "--quiet", *extra,
                  timeout=600)
    return run, time.monotonic() - start


_NOT_THE_FLIGHTS = (*Metrics.WALL, "record")
"""What differs between runs of one flight: its pace, and where (if at all) it was recorded."""


def _figures(run: subprocess.CompletedProcess[str]) -> dict[str, object]:
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    assert data["completed"], data["error"]
    return {k: v for k, v in data.items() if k not in _NOT_THE_FLIGHTS}


def test_joining_a_lockstep_simulator_on_another_host_flies_the_local_flight_to_the_last_digit(
        other_host: Host, short_flight: tuple[dict, Path]) -> None:
    """The local flight: the session's short flight, which ``gcs fly`` flew starting its
    own simulator."""
    endpoint = f"tcp/{other_host.address}:{free_tcp_port()}"
    with SimProcess(CONFIG, endpoint=endpoint, speed="max", lockstep=True,
                    wrap=other_host.command) as sim:
        assert "lockstep 0.25 s" in sim.ready_line
        joined, joined_wall = _fly("--connect", endpoint)
        # flown: a second GCS is refused at once, naming why (the simulator is not fresh)
        again, again_wall = _fly("--connect", endpoint)
    print(f"joined across hosts {joined_wall:.1f} s wall, refused again in "
          f"{again_wall:.1f} s")
    local = {k: v for k, v in short_flight[0].items() if k not in _NOT_THE_FLIGHTS}
    assert _figures(joined) == local
    assert again.returncode == 2 and again.stdout == ""
    assert again.stderr.strip().count("\n") == 0, again.stderr
    assert "gcs fly: error: --connect: " in again.stderr
    assert "is in lockstep with another GCS already" in again.stderr
    assert "start a fresh one for this flight" in again.stderr


def test_a_free_running_simulator_faster_than_real_time_and_speed_with_connect_are_refused(
) -> None:
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    with SimProcess(CONFIG, endpoint=endpoint, speed="max"):
        run, wall = _fly("--connect", endpoint)
    assert run.returncode == 2 and run.stdout == "", run.stdout
    assert run.stderr.startswith("gcs fly: error: --connect: the simulator at "), run.stderr
    assert "runs free at" in run.stderr and "--lockstep" in run.stderr
    assert wall < 30.0  # at once: not a flight of late ticks and stale telemetry
    run, _ = _fly("--connect", endpoint, "--speed", "4")
    assert run.returncode == 2
    assert run.stderr.startswith("gcs fly: error: --speed: paces a simulator started here")


def test_of_two_gcss_joining_one_lockstep_simulator_it_follows_the_first_and_stops_the_other(
) -> None:
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    settings = ZenohSettings(connect=(endpoint,))
    with SimProcess(CONFIG, endpoint=endpoint, speed="max", lockstep=True), \
            GcsApp(TEAM, zenoh_settings=settings, sim_clock=True, lockstep=None) as first, \
            GcsApp(TEAM, zenoh_settings=settings, sim_clock=True, lockstep=None) as second:
        assert first.lockstep and second.lockstep  # both joined the fresh simulator
        first.start()
        second.start()
        outcomes = []
        for app in (first, second):
            try:
                app.clock.sleep_until(5.0)
                outcomes.append("flew")
            except ClockStoppedError as exc:
                outcomes.append(str(exc))
                assert any("in lockstep with another GCS" in e.text for e in app.loop.events())
        assert outcomes.count("flew") == 1, outcomes
        stopped = next(o for o in outcomes if o != "flew")
        assert stopped.startswith("the simulator is in lockstep with another GCS (partner ")
        # a third is refused at once, before it opens a link
        with pytest.raises(ConfigError, match=r"--connect: the simulator at .* is in lockstep "
                                              r"with another GCS already \(at t = "):
            GcsApp(TEAM, zenoh_settings=settings, sim_clock=True, lockstep=None)


@pytest.mark.parametrize(("pace", "late_first"), [(1.0, 0.15), (1.0, 0.0), (0.5, 0.15),
                                                  (1.3, 0.0), (5.0, 0.1)])
def test_a_simulators_pace_is_read_through_a_slow_links_jitter(pace: float,
                                                               late_first: float) -> None:
    """Clock samples every 0.1 s over a link of 0.1 s delay with random extra delays up to
    0.1 s, the first held back ``late_first`` more (a resend): the pace read is the
    simulator's within 5 % (the first and last samples alone read 1.3x for real time)."""
    rng = np.random.default_rng(3)
    sim = np.arange(0.0, 1.6 * pace, 0.1 * pace)
    wall = 100.0 + sim / pace + 0.1 + rng.uniform(0.0, 0.1, len(sim))
    wall[0] += late_first
    wall = np.maximum.accumulate(wall)  # a stream keeps its order
    assert free_pace(wall, sim) == pytest.approx(pace, rel=0.05)
