"""Flight metrics: how well a flight kept its shape, calmed its payload, used its limits.

Fed once per tick with the runtime's snapshot and, in simulation, the latest
ground truth (payload and ropes cannot be measured on real vehicles; those
metrics are then absent). The same numbers come out of ``gcs fly --json`` and,
from a recorded log, ``gcs report``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gcs.loop import Phase, RuntimeSnapshot

__all__ = ["FlightMetrics", "swing_angle"]

#: Phases in which the shape is flown and its error counts.
_FLOWN = (Phase.HOVER, Phase.LIFTING, Phase.FORMATION, Phase.SETTING_DOWN)
#: The payload counts as lifted above this height, m.
LIFTED = 0.05


def swing_angle(vehicles_ned: np.ndarray, payload_ned: np.ndarray) -> float:
    """Angle of the payload from the vertical under the team's centroid, rad."""
    rel = payload_ned - vehicles_ned.mean(axis=0)
    return math.atan2(float(np.hypot(rel[0], rel[1])), max(float(rel[2]), 1e-9))


@dataclass
class FlightMetrics:
    """Running worst cases of one flight."""

    worst_distance_error: float = 0.0
    worst_distance_error_by_phase: dict[str, float] = field(default_factory=dict)
    worst_bank: float = 0.0
    worst_accel_cmd: float = 0.0
    payload_lift: float | None = None
    worst_swing: float | None = None
    rope_tension_min: float | None = None
    rope_tension_max: float | None = None
    start: float | None = None
    end: float = 0.0
    ticks: int = 0
    offboard_exits: int = 0
    _phases: list[str] = field(default_factory=list)
    _streaming_modes: tuple[str, ...] | None = None
    _modes: tuple[str, ...] = ()

    def add(self, snap: RuntimeSnapshot) -> None:
        """Account for one tick of a live flight (with its ground truth in simulation)."""
        self._count_exits(snap.phase, snap.fleet.modes)
        truth = snap.truth
        self.add_tick(snap.fleet.t, snap.phase, distance_errors=snap.distance_errors,
                      tilt=snap.fleet.tilt, accel_cmd=snap.accel_cmd,
                      vehicles_true=None if truth is None else np.array(truth.vehicle_p_ned),
                      payload=None if truth is None else np.array(truth.payload_p_ned),
                      rope_tension=None if truth is None else np.array(truth.rope_tension))

    def add_tick(self, t: float, phase: Phase, *, distance_errors: np.ndarray,
                 tilt: np.ndarray, accel_cmd: np.ndarray, vehicles_true: np.ndarray | None,
                 payload: np.ndarray | None, rope_tension: np.ndarray | None) -> None:
        """Account for one tick from its primitive values (live or read back from a log)."""
        if self.start is None:
            self.start = t
        self.end = t
        self.ticks += 1
        if not self._phases or self._phases[-1] != phase.text:
            self._phases.append(phase.text)
        if phase in _FLOWN and np.all(np.isfinite(distance_errors)):
            e = float(np.abs(distance_errors).max())
            self.worst_distance_error = max(self.worst_distance_error, e)
            by = self.worst_distance_error_by_phase
            by[phase.text] = max(by.get(phase.text, 0.0), e)
        if phase.airborne and np.any(np.isfinite(tilt)):
            self.worst_bank = max(self.worst_bank, float(np.nanmax(tilt)))
        self.worst_accel_cmd = max(self.worst_accel_cmd,
                                   float(np.linalg.norm(accel_cmd, axis=1).max()))
        if payload is None or vehicles_true is None or rope_tension is None:
            return
        height = -float(payload[2])
        self.payload_lift = max(self.payload_lift or 0.0, height)
        if height > LIFTED:
            swing = swing_angle(vehicles_true, payload)
            self.worst_swing = max(self.worst_swing or 0.0, swing)
            lo, hi = float(rope_tension.min()), float(rope_tension.max())
            self.rope_tension_min = lo if self.rope_tension_min is None else min(
                self.rope_tension_min, lo)
            self.rope_tension_max = hi if self.rope_tension_max is None else max(
                self.rope_tension_max, hi)

    def _count_exits(self, phase: Phase, modes: tuple[str, ...]) -> None:
        """Vehicles leaving the mode that flies the GCS's setpoints (OFFBOARD, GUIDED) while
        the team flies on them: each is a vehicle that fell out of the stream."""
        if phase not in _FLOWN:
            self._modes = ()
            return
        if self._streaming_modes is None:  # the modes the take-off handed the team over in
            self._streaming_modes = modes
        if self._modes:
            self.offboard_exits += sum(
                before == want != now
                for before, now, want in zip(self._modes, modes, self._streaming_modes,
                                             strict=True))
        self._modes = modes

    @property
    def duration(self) -> float:
        return 0.0 if self.start is None else self.end - self.start

    def to_json(self, *, wall_seconds: float | None = None) -> dict[str, object]:
        """Stable keys, SI units in the names; None where not measured."""

        def num(x: float | None, digits: int = 4) -> float | None:
            return None if x is None or not math.isfinite(x) else round(float(x), digits)

        return {
            "duration_s": num(self.duration, 3),
            "ticks": self.ticks,
            "phases": list(self._phases),
            "worst_distance_error_m": num(self.worst_distance_error),
            "worst_distance_error_by_phase_m": {k: num(v) for k, v in
                                                self.worst_distance_error_by_phase.items()},
            "payload_lift_m": num(self.payload_lift),
            "worst_swing_rad": num(self.worst_swing),
            "worst_bank_rad": num(self.worst_bank),
            "worst_accel_cmd_m_s2": num(self.worst_accel_cmd),
            "rope_tension_min_N": num(self.rope_tension_min),
            "rope_tension_max_N": num(self.rope_tension_max),
            "offboard_exits": self.offboard_exits,
            "real_time_factor": (num(self.duration / wall_seconds, 2)
                                 if wall_seconds else None),
        }
