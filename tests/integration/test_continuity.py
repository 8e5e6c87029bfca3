"""The team keeps flying through a bad second, against the real simulator.

Lockstep flights (the sim's clock; cannot fail from load): a lost second on
every radio is flown through by itself (or on the operator's resume, with that
policy); a pilot's mode switch is not overruled; a team whose positions
disagree with its shape holds instead of tearing itself apart, and lands if
the disagreement keeps growing; the geofence stops the team and lets it fly
back. One real-time flight: a loop thread stalled for 0.6 s leaves no vehicle
without setpoints (time is the subject there).
"""

from __future__ import annotations

import contextlib
import dataclasses
import threading
import time
from collections.abc import Callable

import numpy as np
import pytest

from gcs.app import GcsApp, SimProcess, free_tcp_port
from gcs.app._scenario import Scenario, ScenarioError, Step, play
from gcs.common import HOLD_KP, HOLD_KV
from gcs.config import Team, load_team
from gcs.loop import FleetState, Phase, RuntimeSnapshot
from gcs.transport import ZenohSettings
from gcs.wire import SETPOINT_MESSAGE, SimMode
from tests.integration.test_setpoint_stream import hovering
from tests.support.flights import break_vehicle, in_formation, sim_sleep

TEAM = load_team("configs/bebop_square.yaml")
OFFBOARD = ("OFFBOARD",) * 4


def with_safety(team: Team, **changes: object) -> Team:
    cfg = team.config
    return dataclasses.replace(team, config=dataclasses.replace(
        cfg, safety=dataclasses.replace(cfg.safety, **changes)))


def fly_sticks(app: GcsApp, seconds: float, forward: float = 0.0, right: float = 0.0,
               each: Callable[[RuntimeSnapshot], None] | None = None) -> None:
    end = app.clock.now() + seconds
    while app.clock.now() < end:
        app.operator.set_sticks(forward, right, 0.0, now=app.clock.now(), source="test")
        sim_sleep(app, 0.25)
        if each is not None and app.runtime.snapshot is not None:
            each(app.runtime.snapshot)


def texts(app: GcsApp) -> list[str]:
    return [e.text for e in app.runtime.events()]


def lose_every_radio(app: GcsApp, seconds: float) -> None:
    for vid in TEAM.formation.ids:
        break_vehicle(app, "cut", vid)
    fly_sticks(app, seconds, forward=0.6)
    for vid in TEAM.formation.ids:
        break_vehicle(app, "restore", vid)


def test_a_lost_second_on_every_radio_is_flown_through() -> None:
    with in_formation() as app:
        fly_sticks(app, 1.0, forward=0.6)
        lose_every_radio(app, 1.2)
        modes_seen: set[str] = set()
        fly_sticks(app, 5.0, forward=0.6, each=lambda s: modes_seen.update(s.fleet.modes))
        snap = app.runtime.snapshot
        assert "HOLD" in modes_seen  # the gap did send them to hold
        assert snap.phase is Phase.FORMATION and snap.fleet.modes == OFFBOARD
        assert snap.moving and snap.demand.forward > 0.0 and not snap.recovery
        assert "recovery: every link fresh for 1 s: re-engaging vehicles 1, 2, 3, 4" \
            in texts(app)
        assert app.runtime.recovery.attempts == 1


def test_setpoints_lost_on_the_way_are_told_by_the_vehicle_and_recovered() -> None:
    """Vehicle 2's setpoints vanish on the way for 1 s while its telemetry flows and the
    GCS sends on time: only the vehicle knows; its failsafe message (as PX4 announces one)
    tells the GCS that the stream, not a pilot, took it out of OFFBOARD."""
    with in_formation() as app:
        fly_sticks(app, 1.0, forward=0.6)
        transport = app.runtime.profiles[2].link.transport
        send = transport.send
        lost = threading.Event()

        def lossy(frame: bytes) -> None:  # a MAVLink 2 frame's message id: bytes 7-9
            if lost.is_set() and int.from_bytes(bytes(frame[7:10]), "little") == \
                    SETPOINT_MESSAGE.id:
                return
            send(frame)

        transport.send = lossy  # type: ignore[method-assign]
        lost.set()
        fly_sticks(app, 1.0, forward=0.6)
        lost.clear()
        assert app.runtime.snapshot.fleet.modes[1] == "HOLD"
        fly_sticks(app, 3.0, forward=0.6)
        snap = app.runtime.snapshot
        assert snap.fleet.modes == OFFBOARD and snap.moving
        assert app.runtime.recovery.attempts == 1
        assert any("re-engaging vehicles 2" in t for t in texts(app))


def test_with_the_operator_policy_the_team_waits_for_resume_and_says_so() -> None:
    with in_formation(with_safety(TEAM, recovery="operator")) as app:
        lose_every_radio(app, 1.2)
        fly_sticks(app, 4.0, forward=0.6)
        snap = app.runtime.snapshot
        assert set(snap.fleet.modes) == {"HOLD"} and not snap.moving
        assert snap.recovery == ("vehicles 1, 2, 3, 4 out of the streaming mode: press "
                                 "Resume to fly them again")
        play(Scenario(name="resume", steps=(Step(action="resume"),)), app.runtime, app.clock)
        fly_sticks(app, 1.0, forward=0.6)
        snap = app.runtime.snapshot
        assert snap.fleet.modes == OFFBOARD and snap.moving and not snap.recovery


def test_a_pilots_mode_switch_is_not_overruled() -> None:
    with in_formation() as app:
        fly_sticks(app, 1.0, forward=0.6)
        app.links.profiles[3].set_mode(SimMode.HOLD)
        fly_sticks(app, 4.0, forward=0.6)
        snap = app.runtime.snapshot
        assert snap.fleet.modes[2] == "HOLD" and not snap.moving
        assert "press Resume" in snap.recovery
        assert app.runtime.recovery.attempts == 0


def shifted(app: GcsApp, offset: Callable[[float], float]) -> None:
    """Vehicle 1's reported position moved north by ``offset(t)`` m: its local frame
    disagrees with the others' (an autopilot's own origin)."""
    table = app.runtime.fleet_table
    read = table.read

    def wrong(now: float) -> FleetState:
        fleet = read(now)
        p = fleet.p_ned.copy()
        p[0, 0] += offset(now)
        return dataclasses.replace(fleet, p_ned=p)

    table.read = wrong  # type: ignore[method-assign]


def true_errors(snap: RuntimeSnapshot) -> float:
    assert snap.truth is not None
    p = np.array(snap.truth.vehicle_p_ned)[:, :2]
    return float(np.abs(TEAM.formation.distance_errors(p)).max())


def test_positions_that_disagree_with_the_shape_hold_the_team_instead_of_tearing_it() -> None:
    """Shape keeping on a vehicle 1.4 m out of place by its frame alone would drag the real
    team apart; holding (each vehicle on its own point) keeps it together, and says why."""
    with in_formation() as app:
        shifted(app, lambda _t: 1.4)
        worst: list[float] = []
        fly_sticks(app, 8.0, each=lambda s: worst.append(true_errors(s)))
        snap = app.runtime.snapshot
        assert snap.safety.hold and not snap.moving and snap.phase is Phase.FORMATION
        assert max(worst) < 0.3, max(worst)
        # each vehicle pulled back to its own point, with no term of another's position
        held = app.runtime.deformation.hold_points
        assert held is not None
        want = -HOLD_KV * snap.fleet.v_ned[:, :2] - HOLD_KP * (snap.fleet.p_ned[:, :2] - held)
        np.testing.assert_allclose(snap.accel_cmd, want, atol=1e-9)
        assert any("from the centroid" in t and "holding (each vehicle on its own point)" in t
                   for t in texts(app))


def test_a_start_out_of_shape_is_not_armed_and_one_seen_once_armed_holds_at_hover() -> None:
    """Vehicle 1 seen 1.4 m out of place from the start (its own origin): the arm is refused,
    naming it (the checks before arming). Seen so only once armed, the team takes off and
    holds at hover, each vehicle on its own point; the real shape does not drift."""
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    with SimProcess(TEAM.source, endpoint=endpoint, speed="max", lockstep=True), \
            GcsApp(TEAM, zenoh_settings=ZenohSettings(connect=(endpoint,)), sim_clock=True,
                   lockstep=True) as app:
        shift = [1.4]
        shifted(app, lambda _t: shift[0])
        app.start()
        with pytest.raises(ScenarioError, match=r"vehicle 1: 1\.40 m from its place"):
            play(Scenario(name="arm", steps=(Step(action="arm"),)), app.runtime, app.clock)
        shift[0] = 0.0
        play(Scenario(name="arm", steps=(Step(action="arm"),)), app.runtime, app.clock)
        shift[0] = 1.4
        play(Scenario(name="up", steps=(Step(action="takeoff"),)), app.runtime, app.clock)
        worst: list[float] = []
        fly_sticks(app, 10.0, each=lambda s: worst.append(true_errors(s)))
        snap = app.runtime.snapshot
        assert snap.phase is Phase.HOVER and snap.safety.hold
        assert max(worst) < 0.1, max(worst)
        assert any("holding (each vehicle on its own point)" in t for t in texts(app))


def test_a_deformation_that_keeps_growing_while_holding_lands_the_team() -> None:
    with in_formation() as app:
        t0 = app.clock.now()
        shifted(app, lambda t: 1.4 + 0.2 * (t - t0))
        fly_sticks(app, 4.0)
        assert app.runtime.phase in (Phase.ABORTING, Phase.LANDING, Phase.LANDED)
        assert any(t.startswith("deformation grew from ") and t.endswith("landing the team")
                   for t in texts(app))


def test_flown_east_at_full_stick_the_team_stops_at_the_fence_and_flies_back() -> None:
    fence = TEAM.config.safety.geofence_xy
    with in_formation() as app:
        east: list[float] = []

        def reach(s: RuntimeSnapshot) -> None:
            assert s.truth is not None
            east.append(max(max(p[1] for p in s.truth.vehicle_p_ned), s.truth.payload_p_ned[1]))

        fly_sticks(app, 30.0, right=1.0, each=reach)
        assert max(east) <= fence, max(east)
        assert east[-1] > fence - TEAM.config.safety.geofence_margin
        warnings = [t for t in texts(app) if t.startswith("at the geofence (east)")]
        assert warnings and app.runtime.phase is Phase.FORMATION
        stopped = east[-1]
        east.clear()
        fly_sticks(app, 8.0, right=-1.0, each=reach)
        assert east[-1] < stopped - 2.0, east[-1]


def test_a_loop_stall_leaves_no_vehicle_without_setpoints() -> None:
    """Real time: the loop thread is held for 0.85 s in one tick (a slow listener), so the
    next tick comes 0.6 s late; the re-send thread keeps every vehicle's setpoints coming,
    and the stall is reported."""
    with hovering() as app:
        stall = threading.Event()
        stall.set()

        def slow_listener(_snap: RuntimeSnapshot) -> None:
            if stall.is_set():
                stall.clear()
                time.sleep(0.85)

        app.runtime.add_listener(slow_listener)
        modes: set[tuple[str, ...]] = set()
        end = time.monotonic() + 3.0
        while time.monotonic() < end:
            if app.runtime.snapshot is not None:
                modes.add(app.runtime.snapshot.fleet.modes)
            time.sleep(0.05)
        stats = app.runtime.stats()
        assert stats.stall_max >= 0.5, stats
        assert stats.setpoint_gap_max < 0.5, stats
        assert modes == {OFFBOARD}, modes
        assert any(t.startswith("loop stalled: tick ") for t in texts(app))


def test_a_frozen_simulator_ends_a_scripted_flight_with_the_reason() -> None:
    """A lockstep simulator that stops (here SIGSTOP, as a hung process) used to leave
    ``gcs fly`` waiting at the step gate for ever: the loop had ended on the stopped clock,
    and no tick ever came to release the scenario. Now it ends with the clock's reason."""
    import json
    import os
    import signal
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-m", "gcs", "fly", "--config",
                             "configs/bebop_square.yaml", "--scenario",
                             "configs/scenarios/short_flight.yaml", "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    sim_pid = None
    try:
        assert proc.stderr is not None
        for line in proc.stderr:  # frozen in flight: after the take-off began
            if "step 2/8" in line:
                break
        children = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True,
                                  text=True, check=False).stdout.split()
        assert len(children) == 1, children
        sim_pid = int(children[0])
        os.kill(sim_pid, signal.SIGSTOP)
        out, _ = proc.communicate(timeout=180)  # a 15 s clock timeout, on a busy machine
        result = json.loads(out.splitlines()[-1])
        assert proc.returncode == 1 and not result["completed"]
        assert "no simulator clock sample" in result["error"], result["error"]
    finally:
        if sim_pid is not None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(sim_pid, signal.SIGCONT)
        if proc.poll() is None:
            proc.kill()
            proc.wait()
