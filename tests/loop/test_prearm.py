"""Checks before arming, through the GCS loop's arm, against scripted autopilots.

Four scripted PX4s and ArduPilots (real pymavlink bytes on UDP,
:mod:`tests.support.scripted_autopilot`) on the paper's square, each with its own
origin and GPS as a real one has. A good start arms (ArduPilot in GUIDED
first); each fault refuses the arm with one error naming the vehicle and the
reason, and no vehicle is sent an arm command. While the team is ready, the
snapshot lists the checks that fail already (:meth:`gcs.loop.Prearm.watch`),
from what the GCS heard, before anyone presses ARM.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import pytest

from gcs.config import GeoPoint, TeamFrameConfig, load_team
from gcs.loop import Phase
from gcs.wire import CopterMode, mavlink
from tests.support.scripted_autopilot import ARM, REF, SET_MODE, SQUARE, Bench, moved, peer_team

SQUARE_IDS = (1, 2, 3, 4)
KINDS = {1: "ardupilot", 2: "ardupilot", 3: "px4", 4: "px4"}
GOOD_TILT = {"ardupilot": 2000.0, "px4": 20.0}  # the square's bank limit, in each one's units


def team_on_field(*, moved_by: dict[int, tuple[float, float]] | None = None,
                  mocap: bool = False,
                  **changes: dict[str, Any]) -> dict[int, tuple[str, dict[str, Any]]]:
    """Each vehicle stands on its place in the square (plus ``moved_by``), booted there (its
    own origin, local position zero), with GPS and a tilt limit at the bank limit;
    ``mocap``: no GPS, no origin, local positions from one motion-capture frame about REF;
    ``changes[vid]`` overrides its options."""
    positions = load_team(SQUARE).formation.positions
    peers = {}
    for k, vid in enumerate(SQUARE_IDS):
        north, east = positions[k] + np.array((moved_by or {}).get(vid, (0.0, 0.0)))
        kind = KINDS[vid]
        options: dict[str, Any] = {"origin": moved(REF, north, east), "gps": True,
                                   "tilt_limit": GOOD_TILT[kind]}
        if mocap:
            options.update(origin=None, gps=False, xy=(north, east))
        options.update(changes.get(f"v{vid}", {}))
        peers[vid] = (kind, options)
    return peers


def refusal(bench: Bench) -> str:
    """Arm; the one error it ended in (every peer left unarmed, never sent an arm)."""
    bench.ready()
    events = bench.arm()
    errors = [e.text for e in events if e.level == "error"]
    assert len(errors) == 1, events
    assert bench.runtime.phase is Phase.READY
    for vid, peer in bench.peers.items():
        assert not peer.armed and peer.commands(ARM) == [], vid
    return errors[0]


def ready_checks(bench: Bench, *vids: int, timeout_s: float = 5.0) -> tuple[str, ...]:
    """Tick while ready until the snapshot's failing checks name exactly vehicles ``vids``,
    one line each (none: until every check passes; they run again every
    :data:`gcs.loop._prearm.READY_CHECK_PERIOD_S`, and an origin may come a moment after
    the team is ready); what they say then."""
    deadline = time.monotonic() + timeout_s
    want = [f"vehicle {vid}" for vid in vids]
    while True:
        snap = bench.runtime.tick()
        assert snap.phase is Phase.READY
        if [line.split(":")[0] for line in snap.prearm] == want:
            return snap.prearm
        assert time.monotonic() < deadline, snap.prearm
        time.sleep(0.1)


def test_a_good_start_arms_with_ardupilot_in_guided_first() -> None:
    with peer_team(team_on_field()) as bench:
        bench.ready()
        assert ready_checks(bench) == ()  # nothing fails before the arm either
        events = bench.arm()
        assert [e for e in events if e.level == "error"] == []
        assert bench.runtime.phase is Phase.ARMED
        peers = bench.peers
    for vid, peer in peers.items():
        assert peer.violations == [] and peer.armed, vid
        if peer.kind == "ardupilot":  # GUIDED before arming (the peer refuses otherwise)
            modes = peer.commands(SET_MODE)
            assert [int(r.msg.param2) for r in modes] == [CopterMode.GUIDED]
            assert modes[0].t < peer.commands(ARM)[0].t


def test_a_vehicle_without_an_origin_is_not_armed() -> None:
    """GPS-less and silent about its origin: no place in the team frame."""
    peers = team_on_field(v3={"gps": False, "reports_origin": False})
    with peer_team(peers) as bench:
        bench.ready()
        shown = ready_checks(bench, 3)
        # shown from what the vehicles said, nothing asked (the arm asks for its origin)
        asked = bench.peers[3].commands(mavlink.MAV_CMD_REQUEST_MESSAGE)
        text = refusal(bench)
    assert asked == []
    assert shown[0].startswith("vehicle 3: no origin of its local frame")
    assert shown[0] in text
    assert text.startswith("arm failed: checks before arming failed: vehicle 3: no origin of "
                           "its local frame"), text
    assert "vehicle 1" not in text and "vehicle 2" not in text and "vehicle 4" not in text


def test_origins_that_disagree_are_not_armed() -> None:
    """set_origin (motion capture): the vehicles take the team origin but vehicle 2, an
    ArduPilot that had set its own origin already (5 m away), keeps it."""
    team_origin = GeoPoint(lat=REF.lat, lon=REF.lon, alt=REF.alt)
    own = moved(REF, 3.0, 4.0)
    peers = team_on_field(mocap=True, v2={"origin": own})
    frame = TeamFrameConfig(mode="set_origin", origin=team_origin)
    with peer_team(peers, team_frame=frame) as bench:
        text = refusal(bench)
        origins = {vid: peer.origin for vid, peer in bench.peers.items()}
    assert "vehicle 2: its origin" in text and "is 5.00 m from the team origin" in text, text
    assert "origins disagree" in text
    for vid in (1, 3, 4):  # given the team origin, and answering with it
        assert f"vehicle {vid}" not in text
        origin = origins[vid]
        assert origin is not None
        assert (origin.lat, origin.lon, origin.alt) == pytest.approx(
            (REF.lat, REF.lon, REF.alt), abs=1e-6)


def test_one_origin_given_to_every_vehicle_arms() -> None:
    """set_origin (motion capture, no GPS): every vehicle takes the team origin and answers
    with it, before the arm."""
    frame = TeamFrameConfig(mode="set_origin", origin=GeoPoint(lat=REF.lat, lon=REF.lon,
                                                               alt=REF.alt))
    with peer_team(team_on_field(mocap=True), team_frame=frame) as bench:
        bench.ready()
        events = bench.arm()
        assert bench.runtime.phase is Phase.ARMED, events
        peers = bench.peers
    for vid, peer in peers.items():
        assert peer.origin is not None and peer.armed, vid
        assert (peer.origin.lat, peer.origin.lon) == pytest.approx((REF.lat, REF.lon), abs=1e-7)


def test_a_team_out_of_shape_is_not_armed() -> None:
    """Vehicle 2 stands 1 m out of its place: it alone is named, with its own 1 m."""
    with peer_team(team_on_field(moved_by={2: (0.6, -0.8)})) as bench:
        bench.ready()
        shown = ready_checks(bench, 2)
        text = refusal(bench)
    assert text == "arm failed: checks before arming failed: " + "; ".join(shown)
    assert text.startswith("arm failed: checks before arming failed: vehicle 2: 1.00 m from "
                           "its place in the team's shape, beyond the analysis' safe "
                           "deformation of 0.17 m"), text
    assert text.count("vehicle ") == 1


def test_an_autopilot_that_tilts_beyond_the_bank_limit_is_not_armed() -> None:
    peers = team_on_field(v1={"tilt_limit": 3000.0}, v4={"tilt_limit": 45.0})
    with peer_team(peers) as bench:
        bench.ready()
        ready_checks(bench)  # not read yet: nothing known to fail
        text = refusal(bench)
        after = ready_checks(bench, 1, 4)  # read by the arm: shown while ready
        sets = [peer.param_sets for peer in bench.peers.values()]
    assert all(line in text for line in after), (after, text)
    assert "vehicle 1: its tilt limit ANGLE_MAX is 30 degrees, above the config's bank limit " \
           "of 20 degrees (limits.bank_deg)" in text, text
    assert "vehicle 4: its tilt limit MPC_TILTMAX_AIR is 45 degrees" in text, text
    assert "limits.autopilot_tilt: set" in text
    assert sets == [[], [], [], []]  # nothing written without being asked


def test_the_gcs_sets_the_tilt_limit_when_asked_and_reads_it_back() -> None:
    peers = team_on_field(v1={"tilt_limit": 3000.0}, v4={"tilt_limit": 45.0})
    with peer_team(peers, autopilot_tilt="set") as bench:
        bench.ready()
        events = bench.arm()
        assert bench.runtime.phase is Phase.ARMED, events
        result = {vid: (peer.param_sets, peer.params, peer.armed)
                  for vid, peer in bench.peers.items()}
        first_arm = min(peer.commands(ARM)[0].t for peer in bench.peers.values())
    assert result[1][0] == [("ANGLE_MAX", 2000.0)] and result[1][1]["ANGLE_MAX"][0] == 2000.0
    assert result[4][0] == [("MPC_TILTMAX_AIR", 20.0)]
    assert math.isclose(result[4][1]["MPC_TILTMAX_AIR"][0], 20.0, abs_tol=1e-6)
    assert result[2][0] == result[3][0] == []
    assert all(armed for _, _, armed in result.values())
    texts = [e.text for e in events if e.level == "info"]
    assert "vehicle 1: tilt limit ANGLE_MAX set from 30 to 20 degrees (limits.bank_deg), read " \
           "back" in texts, texts
    assert "vehicle 4: tilt limit MPC_TILTMAX_AIR set from 45 to 20 degrees " \
           "(limits.bank_deg), read back" in texts
    assert first_arm > max(e.t for e in events if "tilt limit" in e.text) - 1.0
