"""Sim-only truth on the wire: what a real flight cannot measure (payload, ropes).

The simulator publishes one :class:`SimTruth` per sample under
``fleet/<fleet>/sim/truth`` (see :mod:`gcs.link.keys`); viewers and the flight
metrics subscribe. JSON, because it is small, low-rate and readable with any
zenoh tool.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

__all__ = ["SimTruth"]


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
        """Decode; ValueError (naming the fault) on a malformed sample."""
        try:
            d = json.loads(data)
            return cls(t=float(d["t"]), ids=tuple(int(i) for i in d["ids"]),
                       vehicle_p_ned=tuple(tuple(float(x) for x in p)  # type: ignore[misc]
                                           for p in d["vehicle_p_ned"]),
                       payload_p_ned=tuple(float(x) for x in d["payload_p_ned"]),  # type: ignore[arg-type]
                       payload_v_ned=tuple(float(x) for x in d["payload_v_ned"]),  # type: ignore[arg-type]
                       rope_tension=tuple(float(x) for x in d["rope_tension"]))
        except (ValueError, KeyError, TypeError) as exc:
            raise ValueError(f"malformed sim truth sample: {exc}") from None
