"""What the loop records of a flight: the recorder it writes to, and each tick's internals.

The loop sees only :class:`FlightRecorder`, so the flight log (which reads the
loop's phases and snapshots back) sits above the loop.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Protocol

import numpy as np

from gcs.config import Team
from gcs.guidance import MotionDemand
from gcs.link import AutopilotProfile
from gcs.loop._clock import Clock
from gcs.loop._operator import OperatorSnapshot
from gcs.loop._phases import Phase
from gcs.wire import SimTruth

__all__ = ["FlightRecorder", "record_team", "record_tick"]


class FlightRecorder(Protocol):
    """Where the loop records a flight: :class:`gcs.flightlog.TlogRecorder` writes a ``.tlog``."""

    def frame(self, t: float, frame: bytes) -> None:
        """Record one MAVLink frame, in or out."""

    def text(self, t: float, text: str, *, severity: int) -> None:
        """Record a phase change or a warning."""

    def team(self, t: float, *, ids: tuple[int, ...], edges: np.ndarray, distances: np.ndarray,
             accel_norm: float, accel_axis: float) -> None:
        """Record the team, once, before the first tick."""

    def internals(self, t: float, *, arrays: dict[str, np.ndarray],
                  sticks: tuple[float, float, float], scale: float, altitude: float,
                  phase: int) -> None:
        """Record one tick of guidance internals."""


def record_team(recorder: FlightRecorder, team: Team, profiles: Mapping[int, AutopilotProfile],
                clock: Clock) -> None:
    """Record the team, once, and every frame in and out of its links from here on."""
    f, lim = team.formation, team.config.limits
    recorder.team(clock.now(), ids=f.ids, edges=f.edges, distances=f.distances,
                  accel_norm=lim.accel_norm, accel_axis=lim.accel_axis)
    for vid in f.ids:
        profiles[vid].link.add_frame_listener(
            lambda _direction, frame: recorder.frame(clock.now(), frame))


def record_tick(recorder: FlightRecorder, now: float, *, errors: np.ndarray, accel: np.ndarray,
                tilt: np.ndarray, trims: np.ndarray | None, truth: SimTruth | None,
                demand: MotionDemand, op: OperatorSnapshot, phase: Phase) -> None:
    """Record one tick's guidance internals (NaN: unknown); ``trims``: the load-sharing
    altitude trims (None: off); ``truth``: the simulator's, where there is one."""
    arrays = {"dist_err": errors, "acc_cmd": accel, "tilt": tilt}
    if trims is not None:
        arrays["alt_trim"] = trims
    if truth is not None:
        arrays |= {"payload": np.array(truth.payload_p_ned + truth.payload_v_ned),
                   "rope_T": np.array(truth.rope_tension),
                   "veh_true": np.array(truth.vehicle_p_ned)}
    recorder.internals(now, arrays=arrays, sticks=(demand.forward, demand.right, demand.rotate),
                       scale=demand.scale, altitude=op.altitude, phase=int(phase))
