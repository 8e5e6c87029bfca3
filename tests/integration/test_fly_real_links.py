"""Headless flights on real autopilots: ``gcs fly`` and ``gcs.testing.Team.connect`` on a team
whose ``links:`` reach PX4 vehicles over UDP.

The vehicles are the project's simulator presenting itself as PX4 SITL does
(``python -m sim --udp --separate-origins``: PX4's HEARTBEAT, modes and
parameters, one local origin per vehicle, signed with the team key), paced on
the wall clock and never stepped: to the GCS they are four autopilots on UDP
ports. No simulator is started for the flight, so there is no lockstep, no
fault on command and no ground truth. The assertions are on the phases reached
and sane bounds, not on timings, so a loaded machine slows the flight without
failing it.
"""

from __future__ import annotations

import json
import math
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

from gcs.app import SimProcess, free_tcp_port
from gcs.app._simprocess import SimStartError
from gcs.common import ConfigError
from gcs.flightlog import FlightLog
from gcs.testing import SimulatorOnlyError, Team
from tests.support.commands import run_gcs
from tests.support.paths import ROOT, SQUARE
from tests.support.ports import free_udp_ports

#: Every phase of a flight through lift, sticks, set down and land, in order (after
#: "connect", unless every vehicle was heard before the first tick).
FLOWN = ["ready", "armed", "taking off", "hover", "lifting", "formation", "setting down",
         "hover", "landing", "landed"]


def px4_team(folder: Path, base: int) -> Path:
    """The paper's square as four PX4 vehicles on UDP ports ``base``.. (the sim's), signed with
    the team key, alone on its fleet and zenoh (no simulator's truth can reach it)."""
    raw = yaml.safe_load((ROOT / SQUARE).read_text())
    raw["airframe"] = str((ROOT / "configs" / raw["airframe"]).resolve())
    raw["links"] = [{"sysid": v["id"], "transport": f"udpout:127.0.0.1:{base + k}",
                     "profile": "px4", "signing_key": "team"}
                    for k, v in enumerate(raw["vehicles"])]
    raw["gcs"] = {"fleet": f"px4-{uuid.uuid4().hex[:8]}", "zenoh": {"connect": []}}
    raw["flight"] = {"lift_height": 0.3}  # a short lift: the flight is on the wall clock
    path = folder / "px4_square.yaml"
    path.write_text(yaml.safe_dump(raw))
    return path


@pytest.fixture
def px4_sitl(tmp_path: Path) -> Iterator[Path]:
    """Four simulated PX4 vehicles on UDP at 1x, with their own origins; yields the team file
    whose links reach them."""
    for _ in range(3):
        config = px4_team(tmp_path, free_udp_ports(4))
        base = yaml.safe_load(config.read_text())["links"][0]["transport"].rsplit(":", 1)[1]
        try:
            sim = SimProcess(config, endpoint=f"tcp/127.0.0.1:{free_tcp_port()}", speed="1",
                             extra=("--udp", "--udp-base-port", base, "--udp-gcs-port", "0",
                                    "--separate-origins"), ready_timeout=120.0)
        except SimStartError as exc:
            if "cannot" not in str(exc):  # a port taken meanwhile: try others
                raise
            continue
        try:
            yield config
        finally:
            sim.close()
        return
    pytest.fail("no free ports for the PX4 vehicles")


@pytest.mark.long  # a flight at 1x on the wall clock, the CPU mostly idle: among the busy tests
def test_gcs_fly_flies_a_scenario_on_px4_links_on_the_wall_clock(px4_sitl: Path) -> None:
    scenario = px4_sitl.parent / "short.yaml"
    scenario.write_text(yaml.safe_dump({"name": "px4", "steps": [
        {"action": "arm"}, {"action": "takeoff"}, {"action": "lift"},
        {"sticks": {"forward": 0.6}, "duration": 2}, {"action": "set_down"},
        {"action": "land"}]}))
    out = run_gcs("fly", "--config", str(px4_sitl), "--scenario", str(scenario), "--json")
    assert out.returncode == 0, out.stdout + out.stderr
    assert "on the wall clock (no simulator)" in out.stderr
    m = json.loads(out.stdout.splitlines()[-1])
    print(f"gcs fly on PX4 links: {m['duration_s']} s, worst distance error "
          f"{m['worst_distance_error_m']} m, real-time factor {m['real_time_factor']}")
    assert m["completed"] and m["error"] is None
    assert m["phases"][m["phases"][0] == "connect":] == FLOWN
    # what only the simulator's truth measures is absent, not zero
    assert [m[k] for k in ("payload_lift_m", "worst_swing_rad", "rope_tension_min_N",
                           "rope_tension_max_N")] == [None] * 4
    assert 0.0 < m["worst_distance_error_m"] < 0.5
    assert 0.0 < m["worst_bank_rad"] < math.radians(30)
    assert m["ticks"] > 4 * 10  # the 4 Hz loop, for more than 10 s
    assert 0.5 < m["real_time_factor"] <= 1.0  # the flight's clock is the wall clock


def test_a_flight_failing_in_the_air_lands_the_team_before_gcs_fly_exits(
        px4_sitl: Path) -> None:
    """``gcs fly`` on real vehicles once exited at a failed step and left the team hovering
    with no one streaming to it (four ArduCopter SITL copters, in GUIDED, until their own
    failsafes): now it aborts the team, waits for it to land, and then says so."""
    scenario = px4_sitl.parent / "failing.yaml"
    scenario.write_text(yaml.safe_dump({"name": "failing", "steps": [
        {"action": "arm"}, {"action": "takeoff"}, {"action": "lift", "timeout": 0.5}]}))
    out = run_gcs("fly", "--config", str(px4_sitl), "--scenario", str(scenario), "--json")
    assert out.returncode == 1, out.stdout + out.stderr
    m = json.loads(out.stdout.splitlines()[-1])
    assert m["error"].startswith("step 3 (action lift): still lifting after 0.5 s"), m["error"]
    assert m["error"].endswith("; the team was aborted and is landed"), m["error"]
    assert "the flight failed with the team in the air (lifting): holding, then landing it " \
           "before exiting" in out.stderr, out.stderr
    assert m["phases"][-3:] == ["aborting", "landing", "landed"], m["phases"]


def test_a_team_connected_and_closed_in_the_air_is_landed_first(px4_sitl: Path,
                                                                 tmp_path: Path) -> None:
    """A test on real vehicles that fails (or forgets to land) closes its Team in the air:
    the GCS lands the team before it lets go of it."""
    log = tmp_path / "closed.tlog"
    with Team.connect(px4_sitl, record=log) as team:
        team.arm()
        team.takeoff()
        assert team.phase.text == "hover"
    changes = [phase for _t, phase in FlightLog.load(log).phase_changes()]
    assert changes[-3:] == ["aborting", "landing", "landed"], changes


def test_team_connect_flies_px4_links_call_by_call_and_refuses_faults(px4_sitl: Path) -> None:
    with Team.connect(px4_sitl) as team:
        assert team.phase.text in ("connect", "ready")
        t0 = team.time
        team.arm()
        team.takeoff()
        for fault in (lambda: team.cut_link(2, seconds=1.0), lambda: team.restore_link(2),
                      lambda: team.kill(3), lambda: team.gust((1.0, 0.0, 0.0), 1.0)):
            with pytest.raises(SimulatorOnlyError, match="not available on real vehicles"):
                fault()
        team.wait(1.0)
        state = team.state()
        assert state.phase.text == "hover" and state.p_ned.shape == (4, 3)
        assert -state.p_ned[:, 2].min() > 0.3  # airborne (NED: z down)
        with pytest.raises(SimulatorOnlyError, match="ground truth"):
            _ = state.payload_p_ned
        team.land()  # lift, sticks and set down: the test above, through gcs fly
        m = team.metrics()
        assert team.time - t0 > 3.0  # wall seconds
    assert m.phases[-1] == "landed" and "hover" in m.phases
    assert (m.payload_lift_m, m.worst_swing_rad, m.rope_tension_max_N) == (None, None, None)
    assert 0.0 < m.worst_distance_error_m < 0.5
    assert any(e.text == "phase: landed" for e in team.events)


def test_what_real_vehicles_cannot_do_is_refused_with_the_reason(tmp_path: Path) -> None:
    config = px4_team(tmp_path, 30000)  # refused before any port is opened
    scenario = str(ROOT / "configs" / "scenarios" / "short_flight.yaml")
    for args, said in ((("--speed", "max"), "fly on the wall clock: speed 1 only, got 'max'"),
                       (("--speed", "4"), "speed 1 only, got '4'"),
                       (("--connect", "tcp/127.0.0.1:7447"), "--connect: joins a running "
                                                            "simulator"),
                       (("--seeds", "1-2"), "--seeds: the seeds are the simulator's")):
        out = run_gcs("fly", "--config", str(config), "--scenario", scenario, "--quiet", *args,
                      timeout=120)
        assert out.returncode == 2, out.stdout + out.stderr
        assert said in out.stderr and len(out.stderr.strip().splitlines()) == 1, out.stderr
    with pytest.raises(ConfigError) as refused:
        Team.connect(ROOT / SQUARE)
    assert str(refused.value).endswith("links: no px4 or ardupilot link: Team.connect flies "
                                       "real autopilots; fly a simulated team with SimTeam")
