"""Each vehicle's mode against the one the GCS's setpoints need (gcs.loop._vehicle_modes)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gcs.loop import Phase
from gcs.loop._events import EventLog
from gcs.loop._vehicle_modes import COMING_DOWN_DROP_M, VehicleModes
from tests.support.scripted_autopilot import HOVER_THRUST, fleet_state

SQUARE_XY = np.array([[0.5, 0.5], [0.5, -0.5], [-0.5, -0.5], [-0.5, 0.5]])


@dataclass(frozen=True)
class _Modes:
    """What VehicleModes reads of an autopilot profile."""

    streaming_mode: str = "GUIDED"
    landing_modes: frozenset[str] = frozenset({"LAND", "RTL"})


def _modes() -> VehicleModes:
    return VehicleModes([_Modes()] * 4)  # type: ignore[list-item]


def test_coming_down_is_disarmed_landing_or_out_of_mode_and_falling_away() -> None:
    modes = _modes()
    level = fleet_state(SQUARE_XY, HOVER_THRUST)
    assert not modes.coming_down(level).any()
    disarmed = fleet_state(SQUARE_XY, HOVER_THRUST)
    disarmed.armed[0] = False
    assert modes.coming_down(disarmed).tolist() == [True, False, False, False]
    rtl = fleet_state(SQUARE_XY, HOVER_THRUST, modes=("GUIDED", "GUIDED", "RTL", "GUIDED"))
    assert modes.coming_down(rtl).tolist() == [False, False, True, False]
    for drop, down in ((COMING_DOWN_DROP_M - 0.05, False), (COMING_DOWN_DROP_M + 0.05, True)):
        loiter = fleet_state(SQUARE_XY, HOVER_THRUST,
                             modes=("GUIDED", "GUIDED", "GUIDED", "LOITER"))
        loiter.p_ned[3, 2] += drop
        assert modes.coming_down(loiter)[3] == down, drop


def test_the_vehicles_to_re_engage_are_out_of_mode_and_not_coming_down() -> None:
    modes = _modes()
    down = np.array([False, True, False, False])
    out = modes.out_flying((1, 2, 3, 4), ("HOLD", "LAND", "GUIDED", "LOITER"), down)
    assert out == (1, 4)


def test_a_mode_change_is_news_except_a_carrying_vehicle_leaving_its_streaming_mode() -> None:
    modes, log = _modes(), EventLog(lambda: 0.0, None)
    modes.report(fleet_state(SQUARE_XY, HOVER_THRUST), Phase.FORMATION, log)
    assert not log.recent()  # the first modes heard are no change
    modes.report(fleet_state(SQUARE_XY, HOVER_THRUST, modes=("GUIDED", "LOITER", "GUIDED",
                                                              "GUIDED")), Phase.FORMATION, log)
    modes.report(fleet_state(SQUARE_XY, HOVER_THRUST), Phase.HOVER, log)
    modes.report(fleet_state(SQUARE_XY, HOVER_THRUST), Phase.HOVER, log)  # unchanged: silent
    assert [(e.level, e.text) for e in log.recent()] == [
        ("warning", "vehicle 2: mode LOITER (was GUIDED)"),
        ("info", "vehicle 2: mode GUIDED (was LOITER)")]
