"""What the loop records of each tick (gcs.loop._record.record_tick)."""

from __future__ import annotations

import numpy as np

from gcs.guidance import MotionDemand
from gcs.loop import OperatorSnapshot, Phase
from gcs.loop._record import record_tick
from gcs.wire import SimTruth


class _Internals:
    def __init__(self) -> None:
        self.ticks: list[dict[str, object]] = []

    def internals(self, t: float, *, arrays: dict[str, np.ndarray],
                  sticks: tuple[float, float, float], scale: float, altitude: float,
                  phase: int) -> None:
        self.ticks.append({"t": t, "arrays": arrays, "sticks": sticks, "scale": scale,
                           "altitude": altitude, "phase": phase})


def _record(trims: np.ndarray | None, truth: SimTruth | None) -> dict[str, object]:
    rec = _Internals()
    op = OperatorSnapshot(demand=MotionDemand(), altitude=1.7, altitude_target=2.0,
                          scale_target=1.0, guidance_on=True, source="test")
    record_tick(rec, 3.0, errors=np.zeros(6), accel=np.ones((4, 2)),  # type: ignore[arg-type]
                tilt=np.zeros(4), trims=trims, truth=truth,
                demand=MotionDemand(forward=0.5, right=-0.1, rotate=0.2, scale=1.1), op=op,
                phase=Phase.FORMATION)
    assert len(rec.ticks) == 1
    return rec.ticks[0]


def test_a_real_flights_tick_has_the_guidance_internals_and_no_truth() -> None:
    tick = _record(None, None)
    assert isinstance(tick["arrays"], dict)
    assert set(tick["arrays"]) == {"dist_err", "acc_cmd", "tilt"}
    assert tick["sticks"] == (0.5, -0.1, 0.2) and tick["scale"] == 1.1
    assert tick["altitude"] == 1.7 and tick["phase"] == int(Phase.FORMATION) and tick["t"] == 3.0


def test_trims_and_the_simulators_truth_are_recorded_where_there_are_some() -> None:
    truth = SimTruth(t=3.0, ids=(1, 2, 3, 4), payload_p_ned=(0.0, 0.1, -0.2),
                     payload_v_ned=(0.0, 0.0, 0.0), rope_tension=(1.0, 1.1, 1.2, 1.3),
                     vehicle_p_ned=((0.0, 0.0, -1.0),) * 4)
    arrays = _record(np.full(4, 0.01), truth)["arrays"]
    assert isinstance(arrays, dict)
    assert set(arrays) == {"dist_err", "acc_cmd", "tilt", "alt_trim", "payload", "rope_T",
                           "veh_true"}
    assert arrays["payload"].tolist() == [0.0, 0.1, -0.2, 0.0, 0.0, 0.0]
