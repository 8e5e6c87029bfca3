"""Metric definitions: the payload's swing, the phases a flight's figures count."""

from __future__ import annotations

import numpy as np
import pytest

from gcs.flightlog import FlightMetrics
from gcs.flightlog._metrics import swing_angle
from gcs.loop import Phase


def test_swing_angle() -> None:
    vehicles = np.array([[0.5, 0.5, -2.0], [-0.5, 0.5, -2.0], [-0.5, -0.5, -2.0],
                         [0.5, -0.5, -2.0]])
    assert swing_angle(vehicles, np.array([0.0, 0.0, -1.0])) == pytest.approx(0.0)
    assert swing_angle(vehicles, np.array([1.0, 0.0, -1.0])) == pytest.approx(np.pi / 4)


def test_metrics_count_only_flown_phases() -> None:
    m = FlightMetrics()
    kw = {"tilt": np.zeros(4), "accel_cmd": np.zeros((4, 2)), "vehicles_true": None,
          "payload": None, "rope_tension": None}
    m.add_tick(0.0, Phase.TAKING_OFF, distance_errors=np.array([0.5]), **kw)
    m.add_tick(0.25, Phase.FORMATION, distance_errors=np.array([0.1, -0.2]), **kw)
    m.add_tick(0.5, Phase.HOVER, distance_errors=np.array([0.05]), **kw)
    assert m.worst_distance_error == pytest.approx(0.2)
    assert m.worst_distance_error_by_phase == {"formation": 0.2, "hover": 0.05}
    assert m.duration == pytest.approx(0.5)
    assert m.to_json()["phases"] == ["taking off", "formation", "hover"]
