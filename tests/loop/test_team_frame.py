"""One team frame: autopilots each with their own local origin, placed in one NED frame.

Four scripted autopilots (real pymavlink bytes on UDP) stand on the paper's
square, turned and moved on a field; each set its local origin where it
booted, elsewhere, so its LOCAL_POSITION_NED is its own. ArduPilots report
their origin (GPS_GLOBAL_ORIGIN); PX4s here only their GLOBAL_POSITION_INT
beside LOCAL_POSITION_NED. The GCS must place all four where they stand.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from gcs.common import ConfigError
from gcs.config import GeoPoint, TeamFrameConfig, load_team
from gcs.loop import Runtime
from tests.support.scripted_autopilot import REF, SQUARE, moved, peer_team

HEADING = math.radians(30.0)
CENTRE = np.array([3.0, -2.0])  # the square's centre on the field, m north and east of REF
BOOTED = np.array([[0.0, 0.0], [0.4, -0.3], [-1.2, 2.0], [5.0, 1.0]])
"""Where each vehicle booted (set its origin), m from where it stands now."""


def standing(positions: np.ndarray) -> np.ndarray:
    """Where the square's vehicles stand on the field, m north and east of REF."""
    c, s = math.cos(HEADING), math.sin(HEADING)
    return CENTRE + positions @ np.array([[c, s], [-s, c]])


def own_origins(reporting: dict[int, bool]) -> dict[int, tuple[str, dict[str, Any]]]:
    """The four peers: origin where each booted, local position from there, GPS; those
    ``reporting`` their origin are ArduPilots, the others PX4s without GPS_GLOBAL_ORIGIN."""
    team = load_team(SQUARE)
    where = standing(team.formation.positions)
    peers = {}
    for k, vid in enumerate(team.formation.ids):
        booted = where[k] + BOOTED[k]
        peers[vid] = ("ardupilot" if reporting[vid] else "px4",
                      {"origin": moved(REF, *booted), "xy": tuple(-BOOTED[k]), "gps": True,
                       "reports_origin": reporting[vid], "tilt_limit": 20.0 if not
                       reporting[vid] else 2000.0})
    return peers


def placed(runtime: Runtime, timeout_s: float = 10.0) -> np.ndarray:
    """The team's horizontal positions once every vehicle is placed."""
    deadline = time.monotonic() + timeout_s
    while True:
        p = runtime.fleet_table.read(runtime.clock.now()).p_ned[:, :2]
        if np.isfinite(p).all():
            time.sleep(0.3)  # a few more pairs into the medians
            return runtime.fleet_table.read(runtime.clock.now()).p_ned[:, :2]
        assert time.monotonic() < deadline, f"not placed: {p}"
        time.sleep(0.05)


@pytest.mark.parametrize("origin", [None, GeoPoint(lat=REF.lat, lon=REF.lon, alt=REF.alt)],
                         ids=["mean-origin", "config-origin"])
def test_four_autopilots_with_their_own_origins_are_placed_in_one_frame(
        origin: GeoPoint | None) -> None:
    reporting = {1: True, 2: True, 3: False, 4: False}
    frame = TeamFrameConfig(origin=origin)  # auto: global, for px4 and ardupilot links
    with peer_team(own_origins(reporting), team_frame=frame) as bench:
        assert bench.runtime.team_frame.mode == "global"
        p = placed(bench.runtime)
        events = [e.text for e in bench.runtime.events()]
    team = load_team(SQUARE)
    truth = standing(team.formation.positions)
    if origin is None:  # the team origin is the mean of the vehicles' own
        truth = truth - (truth + BOOTED).mean(axis=0)
    error = np.linalg.norm(p - truth, axis=1)
    print(f"team frame: largest placement error {error.max() * 100:.2f} cm ({origin=})")
    assert error.max() < 0.015, (p, truth)  # lat/lon carry 1e-7 degrees: about a centimetre
    # the shape is the square: every distance as desired
    assert np.abs(team.formation.distance_errors(p)).max() < 0.02
    for vid in (1, 2):
        assert any(t.startswith(f"vehicle {vid}: local origin") and "GPS_GLOBAL_ORIGIN" in t
                   for t in events), events
    for vid in (3, 4):
        assert any(t.startswith(f"vehicle {vid}: local origin") and "GLOBAL_POSITION_INT" in t
                   for t in events), events
    assert any(t.startswith("team frame: origin") for t in events) == (origin is None)


def test_shared_frames_are_taken_as_they_are() -> None:
    """``shared``: the local positions are the team frame's, whatever the origins say."""
    peers = own_origins({1: True, 2: True, 3: True, 4: True})
    with peer_team(peers, team_frame=TeamFrameConfig(mode="shared")) as bench:
        time.sleep(0.5)
        p = bench.runtime.fleet_table.read(bench.runtime.clock.now()).p_ned[:, :2]
    np.testing.assert_allclose(p, -BOOTED)


@pytest.mark.parametrize(("section", "field", "words"), [
    ({"mode": "set_origin"}, "team_frame.origin", "set_origin needs the origin"),
    ({"mode": "gps"}, "team_frame.mode", "must be one of"),
    ({"origin": {"lat": 95.0, "lon": 8.0, "alt": 400.0}}, "team_frame.origin.lat",
     "at most 90"),
])
def test_a_wrong_team_frame_section_is_one_line(tmp_path: Path, section: dict[str, Any],
                                                field: str, words: str) -> None:
    data = yaml.safe_load(SQUARE.read_text())
    data["airframe"] = str(SQUARE.parent / "airframes" / "bebop2.yaml")
    data["team_frame"] = section
    path = tmp_path / "team.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError) as info:
        load_team(path)
    text = str(info.value)
    assert "\n" not in text and text.startswith(f"{path}: {field}") and words in text, text
