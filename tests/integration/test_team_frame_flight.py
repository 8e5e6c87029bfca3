"""End to end: the simulator with one origin per vehicle, flown in the GCS's team frame.

``python -m sim --separate-origins`` gives every simulated vehicle its own local
origin where it stands, as a GPS autopilot sets its EKF origin at its first
fix: every LOCAL_POSITION_NED starts at (0, 0). The GCS on ``team_frame:
global`` places them from their GPS_GLOBAL_ORIGIN and flies the short paper
flight (lift, translate, spin, set down, land) in lockstep; the worst distance
error must be that of the same flight with one shared origin, within 0.02 m.
Taken as one frame instead, the same positions scattered four ArduCopters
(worst error 21.5 m).
"""

from __future__ import annotations

import dataclasses
import re
from typing import Any

import numpy as np
import pytest

from gcs.app import GcsApp, SimProcess, free_tcp_port, load_scenario
from gcs.app._scenario import play
from gcs.config import TeamFrameConfig, load_team
from gcs.flightlog import FlightMetrics
from gcs.loop import GatedClock
from gcs.transport import ZenohSettings
from tests.support.paths import ROOT

CONFIG = ROOT / "configs" / "bebop_square.yaml"
SHORT = ROOT / "configs" / "scenarios" / "short_flight.yaml"

pytestmark = pytest.mark.skipif(
    "separate_origins" not in (ROOT / "sim" / "_options.py").read_text(),
    reason="the simulator has no --separate-origins yet")


def fly_short(*, separate: bool) -> tuple[dict[str, Any], list[str]]:
    """The short flight as ``gcs fly`` flies it (lockstep, the scenario at ticks): its
    metrics and its events."""
    team = load_team(CONFIG)
    if separate:
        frame = TeamFrameConfig(mode="global")
        team = dataclasses.replace(team, config=dataclasses.replace(team.config,
                                                                    team_frame=frame))
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    sim = SimProcess(CONFIG, endpoint=endpoint, speed="max", lockstep=True,
                     extra=("--separate-origins",) if separate else (), ready_timeout=120.0)
    metrics = FlightMetrics()
    try:
        with GcsApp(team, zenoh_settings=ZenohSettings(mode="peer", connect=(endpoint,)),
                    sim_clock=True, lockstep=True) as app:
            app.add_listener(lambda snap, _truth: metrics.add(snap))
            with app.gate.participant():
                app.start()
                play(load_scenario(SHORT), app.loop, GatedClock(app.clock, app.gate))
            events = [e.text for e in app.loop.events()]
            assert app.loop.team_frame.mode == ("global" if separate else "shared")
    finally:
        sim.close()
    return metrics.to_json(), events


def test_separate_origins_fly_the_short_flight_as_one_origin_does() -> None:
    shared, _ = fly_short(separate=False)
    separate, events = fly_short(separate=True)
    worst = shared["worst_distance_error_m"], separate["worst_distance_error_m"]
    print(f"worst distance error: one origin {worst[0]:.4f} m, separate origins "
          f"{worst[1]:.4f} m")
    # the local frames really were apart: each origin where its vehicle started, a corner of
    # the square (0.71 m from the centre, the team origin)
    for vid in (1, 2, 3, 4):
        placed = [re.fullmatch(r".*: local origin ([-+.0-9]+) m north, ([-+.0-9]+) m east in "
                               r"the team frame \(from GPS_GLOBAL_ORIGIN\)", t)
                  for t in events if t.startswith(f"vehicle {vid}: local origin")]
        assert placed and placed[0] is not None, events
        offset = float(np.hypot(float(placed[0][1]), float(placed[0][2])))
        assert 0.6 < offset < 0.8, (vid, placed[0][0])
    assert separate["phases"] == shared["phases"]
    assert abs(worst[1] - worst[0]) <= 0.02, worst
