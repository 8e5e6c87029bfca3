"""The figures of a flight, as ``gcs fly --json`` prints them, as attributes to assert on.

Why a class of its own: a test reads ``m.worst_distance_error_m`` (typed, and a
typo is an AttributeError, not a None), and the same names as the command's
JSON keys, so a figure means one thing whether a scenario or a test flew it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

__all__ = ["Metrics"]


@dataclass(frozen=True)
class Metrics:
    """The figures of one flight so far; SI units in the names, None where not measured
    (payload and ropes: only with the simulator's ground truth)."""

    duration_s: float
    ticks: int
    phases: tuple[str, ...]
    worst_distance_error_m: float
    worst_distance_error_by_phase_m: Mapping[str, float]
    payload_lift_m: float | None
    worst_swing_rad: float | None
    worst_bank_rad: float
    worst_accel_cmd_m_s2: float
    rope_tension_min_N: float | None  # noqa: N815 (the name of `gcs fly --json`)
    rope_tension_max_N: float | None  # noqa: N815
    offboard_exits: int
    real_time_factor: float | None
    loop_stall_max_s: float
    setpoint_gap_max_s: float
    recoveries: int

    #: The figures that measure the machine (wall time), not the flight.
    WALL = ("real_time_factor",)

    @classmethod
    def from_json(cls, figures: Mapping[str, object]) -> Metrics:
        """From the figures of :meth:`gcs.app.HeadlessFlight.figures` (``gcs fly --json``);
        a figure always measured but not finite (None there) is NaN here, so that any
        bound on it fails."""
        names = {f.name for f in dataclasses.fields(cls)}
        if set(figures) != names:
            raise ValueError(f"the flight's figures changed: {sorted(set(figures) ^ names)} "
                             f"(update gcs.testing.Metrics)")
        values: dict[str, Any] = dict(figures)
        for name in ("duration_s", "worst_distance_error_m", "worst_bank_rad",
                     "worst_accel_cmd_m_s2", "loop_stall_max_s", "setpoint_gap_max_s"):
            if values[name] is None:
                values[name] = math.nan
        values["phases"] = tuple(values["phases"])
        return cls(**values)

    def to_dict(self) -> dict[str, object]:
        """The figures as ``gcs fly --json`` has them."""
        out = dataclasses.asdict(self)
        out["phases"] = list(self.phases)
        out["worst_distance_error_by_phase_m"] = dict(self.worst_distance_error_by_phase_m)
        return out

    def flight(self) -> dict[str, object]:
        """The figures of the flight alone (:data:`WALL` left out): the same, to the last
        digit, on every run of one seed."""
        return {k: v for k, v in self.to_dict().items() if k not in self.WALL}
