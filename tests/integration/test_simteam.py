"""``gcs.testing.SimTeam``: a simulated team flown from a test, in lockstep, with faults.

Real parts: the simulator process, zenoh on loopback, signed MAVLink, the GCS's
loop. One flight in turbulence (``gusts=0.5``) with a timed cut link, a gust and a
killed vehicle is flown twice with the same seed (the second with a CPU hog beside
it): the faults act at the sim time of the call and end on the sim's clock, the gust
pushes the team, the kill fails the next step naming the vehicle, and the two flights'
figures are the same to the last digit.
"""

from __future__ import annotations

import contextlib
import socket
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest

from gcs.common import ConfigError
from gcs.testing import FlightError, Metrics, SimTeam
from sim._faults import ControlAction, ControlCommand, parse_control

SQUARE = "configs/bebop_square.yaml"


@dataclass
class Flown:
    """What a test reads of one flight with faults."""

    metrics: Metrics
    cut_at: float
    gust_at: float
    drift_east: tuple[float, float]  # the team's centroid east before and after the gust, m
    kill_error: str
    sim_log: list[str]


def fly_with_faults(seed: int, *, hog: bool = False) -> Flown:
    """The flight; ``hog``: with a CPU hog beside it once the simulator is up."""
    with SimTeam(SQUARE, seed=seed, gusts=0.5) as team, busy(hog):
        assert team._flight.sim is not None and "gusts 0.5 m/s" in team._flight.sim.ready_line
        team.arm()
        team.takeoff()
        team.lift()
        team.sticks(forward=1.0, seconds=2)
        cut_at = team.time
        team.cut_link(3, seconds=1.0)
        team.sticks(right=0.5, seconds=2)
        before = team.state()
        gust_at = team.time
        team.gust((0.0, 4.0, 0.0), seconds=2.0)
        team.wait(3)
        after = team.state()
        assert before.true_p_ned is not None and after.true_p_ned is not None
        assert team.phase.text == "formation"
        sim = team._flight.sim
        assert sim is not None
        log = list(sim.stderr_tail)
        team.kill(2)
        with pytest.raises(FlightError) as failed:
            team.wait(10)
        team.wait_for("landing", timeout=10)
        return Flown(metrics=team.metrics(), cut_at=cut_at,
                     gust_at=gust_at,
                     drift_east=(float(before.true_p_ned[:, 1].mean()),
                                 float(after.true_p_ned[:, 1].mean())),
                     kill_error=str(failed.value), sim_log=log)


@contextlib.contextmanager
def busy(hog: bool) -> Iterator[None]:
    """A process spinning on a core meanwhile (if ``hog``)."""
    if not hog:
        yield
        return
    spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        yield
    finally:
        spinner.kill()
        spinner.wait()


@pytest.fixture(scope="module")
def flown() -> Flown:
    return fly_with_faults(seed=3)


def test_faults_act_at_the_sim_time_of_the_call_and_end_on_the_sims_clock(
        flown: Flown) -> None:
    log = "\n".join(flown.sim_log)
    cut, gust = flown.cut_at, flown.gust_at
    assert f"vehicle 3 cut off at t = {cut:.3f} s" in log, log
    assert f"vehicle 3 restored at t = {cut + 1.0:.3f} s (timed cut)" in log, log
    assert f"gust of (0.0, 4.0, 0.0) m/s (NED) for 2 s at t = {gust:.3f} s" in log, log
    assert f"gust over at t = {gust + 2.0:.3f} s" in log, log
    east0, east1 = flown.drift_east
    assert east1 - east0 > 0.15, flown.drift_east  # 4 m/s from the west pushed the team east


def test_a_killed_vehicle_fails_the_next_step_naming_it(flown: Flown) -> None:
    assert flown.kill_error.startswith("wait(): the flight was aborted"), flown.kill_error
    assert "vehicle 2" in flown.kill_error


def test_the_metrics_are_those_of_gcs_fly(flown: Flown) -> None:
    m = flown.metrics
    assert m.phases[-2:] == ("aborting", "landing")  # with the tick the test saw last
    assert m.payload_lift_m is not None and m.payload_lift_m > 0.9
    assert 0.0 < m.worst_distance_error_m < 0.6
    assert m.recoveries == 1 and m.offboard_exits >= 1  # vehicle 3 fell into HOLD, came back
    assert set(m.to_dict()) - set(m.flight()) == {"real_time_factor"}


def test_the_same_seed_flies_the_same_flight_to_the_last_digit_under_load(
        flown: Flown) -> None:
    again = fly_with_faults(seed=3, hog=True)
    assert again.metrics.flight() == flown.metrics.flight()
    assert (again.cut_at, again.gust_at, again.drift_east) == \
        (flown.cut_at, flown.gust_at, flown.drift_east)


def test_bad_arguments_are_one_line_faults_act_at_their_tick_and_a_failing_test_leaves_nothing(
) -> None:
    with pytest.raises(ValueError, match="speed='max' needs lockstep"):
        SimTeam(SQUARE, lockstep=False)
    with pytest.raises(ValueError, match="speed must be a positive number"):
        SimTeam(SQUARE, speed=-1.0)
    with pytest.raises(ZeroDivisionError), SimTeam(SQUARE) as team:
        sim = team._flight.sim
        assert sim is not None and sim.alive() and team.phase.text in ("connect", "ready")
        with pytest.raises(ConfigError, match=r"SimTeam\.sticks: sticks\.forward"):
            team.sticks(forward=2.0, seconds=1)
        with pytest.raises(ConfigError, match=r"above guidance\.scale_max"):
            team.scale(5.0)
        with pytest.raises(ValueError, match="no vehicle 9"):
            team.cut_link(9)
        with pytest.raises(ValueError, match="wind_ned must be 3 numbers"):
            team.gust((1.0, 2.0), seconds=1)
        with pytest.raises(ValueError, match="seconds must be above 0"):
            team.gust((1.0, 2.0, 0.0), seconds=0)
        with pytest.raises(FlightError, match="sticks move the team in formation flight only"):
            team.sticks(forward=1.0, seconds=1)
        state = team.state()  # the tick the test sees: the team on the ground
        assert state.ids == (1, 2, 3, 4) and abs(state.t - team.time) < 1e-9
        team.wait(1.0)
        state = team.state()
        assert state.true_p_ned is not None and state.rope_tension is not None
        assert np.allclose(state.p_ned[:, :2], state.true_p_ned[:, :2], atol=0.05)
        # every fault acts at the tick it was called in (a put on the control key was
        # overtaken by the tick's ack about once in 30)
        called = []
        for _ in range(40):
            called.append(f"vehicle 3 cut off at t = {team.time:.3f} s")
            team.cut_link(3, seconds=0.125)
            team.wait(0.25)
        acted = [line.removeprefix("sim: ") for line in sim._err if "cut off" in line]
        assert acted == called
        endpoint = team.endpoint
        1 / 0  # noqa: B018 (a test body that fails)
    assert sim is not None and not sim.alive()
    host, port = endpoint.removeprefix("tcp/").rsplit(":", 1)
    with socket.socket() as s:
        assert s.connect_ex((host, int(port))) != 0, f"{endpoint} still open"
    with pytest.raises(RuntimeError, match="closed"):
        team.wait(1)


def test_the_sim_takes_what_simteam_sends_and_refuses_the_rest() -> None:
    gust = ControlCommand(ControlAction.GUST, 0, 3.0, (2.0, 0.0, 0.0))
    assert parse_control(b'{"action": "gust", "sysid": 0, "ned": [2.0, 0.0, 0.0], '
                         b'"seconds": 3.0}') == gust
    assert parse_control(gust.to_bytes()) == gust
    assert parse_control(b'{"action": "cut", "sysid": 3, "seconds": 1.0}') == \
        ControlCommand(ControlAction.CUT, 3, 1.0)
    for bad, why in [
            (b'{"action": "gust", "sysid": 1, "ned": [2, 0, 0], "seconds": 3}', "sysid 0"),
            (b'{"action": "gust", "sysid": 0, "ned": [2, 0], "seconds": 3}', "3 numbers"),
            (b'{"action": "gust", "sysid": 0, "ned": [2, 0, 1e9], "seconds": 3}', "within|lie"),
            (b'{"action": "gust", "sysid": 0, "ned": [2, 0, NaN], "seconds": 3}', "lie in"),
            (b'{"action": "gust", "sysid": 0, "ned": [2, 0, 0]}', "takes ned, seconds"),
            (b'{"action": "cut", "sysid": 3, "seconds": -1}', "lie in|above 0"),
            (b'{"action": "cut", "sysid": 3, "seconds": true}', "numbers"),
            (b'{"action": "kill", "sysid": 3, "seconds": 1}', "takes nothing more")]:
        with pytest.raises(ValueError, match=why):
            parse_control(bad)

