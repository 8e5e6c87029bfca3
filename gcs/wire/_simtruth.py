"""Sim-only truth on the wire: what a real flight cannot measure (payload, ropes).

The simulator publishes one :class:`SimTruth` per sample under
``fleet/<fleet>/sim/truth`` (see :mod:`gcs.wire.keys`); viewers and the flight
metrics subscribe. JSON, because it is small, low-rate and readable with any
zenoh tool.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

__all__ = ["SimTruth", "vec3"]


@dataclass(frozen=True)
class SimTruth:
    """One sample of the simulator's ground truth (NED, SI)."""

    t: float  # sim time, s
    ids: tuple[int, ...]  # vehicle system ids, in the order of the arrays below
    vehicle_p_ned: tuple[tuple[float, float, float], ...]
    payload_p_ned: tuple[float, float, float]
    payload_v_ned: tuple[float, float, float]
    rope_tension: tuple[float, ...]  # N, per vehicle

    def to_bytes(self) -> bytes:
        return json.dumps({
            "t": self.t, "ids": self.ids, "vehicle_p_ned": self.vehicle_p_ned,
            "payload_p_ned": self.payload_p_ned, "payload_v_ned": self.payload_v_ned,
            "rope_tension": self.rope_tension,
        }).encode()

    @classmethod
    def from_bytes(cls, data: bytes) -> SimTruth:
        """Decode; ValueError (naming the fault) on a malformed sample: vectors of three,
        one position and one rope tension per vehicle id."""
        try:
            d = json.loads(data)
            ids = tuple(int(i) for i in d["ids"])
            vehicles = tuple(vec3(p, "vehicle_p_ned") for p in d["vehicle_p_ned"])
            tensions = tuple(float(x) for x in d["rope_tension"])
            for name, values in (("vehicle_p_ned", vehicles), ("rope_tension", tensions)):
                if len(values) != len(ids):
                    raise ValueError(f"{name}: {len(values)} entries for {len(ids)} vehicles")
            return cls(t=float(d["t"]), ids=ids, vehicle_p_ned=vehicles,
                       payload_p_ned=vec3(d["payload_p_ned"], "payload_p_ned"),
                       payload_v_ned=vec3(d["payload_v_ned"], "payload_v_ned"),
                       rope_tension=tensions)
        except (ValueError, KeyError, TypeError) as exc:
            raise ValueError(f"malformed sim truth sample: {exc}") from None


def vec3(values: Any, name: str = "vector") -> tuple[float, float, float]:
    """Three floats from a sequence (a JSON list, a numpy row), or ValueError naming the
    field: the one conversion of every producer of a :class:`SimTruth`."""
    v = tuple(float(x) for x in values)
    if len(v) != 3:
        raise ValueError(f"{name}: {len(v)} values, not 3")
    return v[0], v[1], v[2]
