"""Sim-only truth on the wire: what a real flight cannot measure (payload, ropes).

The simulator publishes one :class:`SimTruth` per sample under
``fleet/<fleet>/sim/truth`` (see :mod:`gcs.wire.keys`); viewers and the flight
metrics subscribe. JSON, because it is small, low-rate and readable with any
zenoh tool.

Anyone on the fabric can publish on the truth key: :meth:`SimTruth.from_bytes`
refuses a payload longer than :data:`TRUTH_MAX_BYTES` before parsing it, and
turns whatever the parser or a conversion raises on hostile input (deep
nesting, numbers too large for a float) into one ValueError.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

__all__ = ["TRUTH_MAX_BYTES", "SimTruth", "vec3"]

TRUTH_MAX_BYTES = 256 * 1024
"""Longest truth sample taken, bytes (255 vehicles take about 25 kB)."""


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
        """Decode; ValueError (naming the fault), and nothing else, on a malformed sample:
        at most :data:`TRUTH_MAX_BYTES`, vectors of three finite values, system ids 1..255
        each once, one position and one rope tension per vehicle, ``t`` >= 0."""
        if len(data) > TRUTH_MAX_BYTES:
            raise ValueError(f"malformed sim truth sample: {len(data)} bytes, more than "
                             f"{TRUTH_MAX_BYTES}")
        try:
            return cls._parse(data)
        except (ValueError, KeyError, TypeError) as exc:
            raise ValueError(f"malformed sim truth sample: {exc}") from None
        except Exception as exc:  # RecursionError, OverflowError, ...: hostile input
            raise ValueError(f"malformed sim truth sample: {type(exc).__name__}") from None

    @classmethod
    def _parse(cls, data: bytes) -> SimTruth:
        d = json.loads(data)
        ids = tuple(_sysid(i) for i in d["ids"])
        if len(set(ids)) != len(ids):
            raise ValueError("ids: a system id appears twice")
        vehicles = tuple(vec3(p, "vehicle_p_ned") for p in d["vehicle_p_ned"])
        tensions = tuple(float(x) for x in d["rope_tension"])
        for name, values in (("vehicle_p_ned", vehicles), ("rope_tension", tensions)):
            if len(values) != len(ids):
                raise ValueError(f"{name}: {len(values)} entries for {len(ids)} vehicles")
        truth = cls(t=float(d["t"]), ids=ids, vehicle_p_ned=vehicles,
                    payload_p_ned=vec3(d["payload_p_ned"], "payload_p_ned"),
                    payload_v_ned=vec3(d["payload_v_ned"], "payload_v_ned"),
                    rope_tension=tensions)
        if not truth.t >= 0.0:
            raise ValueError(f"t: must be >= 0 s, got {truth.t}")
        values = (truth.t, *truth.payload_p_ned, *truth.payload_v_ned, *tensions,
                  *(x for p in vehicles for x in p))
        if not all(math.isfinite(x) for x in values):
            raise ValueError("values must be finite")
        return truth


def _sysid(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 255:
        raise ValueError(f"ids: a system id must be an integer 1..255, got {value!r:.40}")
    return value


def vec3(values: Any, name: str = "vector") -> tuple[float, float, float]:
    """Three floats from a sequence (a JSON list, a numpy row), or ValueError naming the
    field: the one conversion of every producer of a :class:`SimTruth`."""
    v = tuple(float(x) for x in values)
    if len(v) != 3:
        raise ValueError(f"{name}: {len(v)} values, not 3")
    return v[0], v[1], v[2]
