"""What one tick leaves for the page and the metrics, and how the ticks kept time."""

from __future__ import annotations

import collections
from dataclasses import dataclass, field

import numpy as np

from gcs.guidance import MotionDemand
from gcs.loop._deformation import Deformation
from gcs.loop._events import Event
from gcs.loop._fleet import FleetState
from gcs.loop._geofence import FenceVerdict
from gcs.loop._operator import OperatorSnapshot
from gcs.loop._phases import Phase
from gcs.loop._safety import SafetyVerdict
from gcs.wire import SimTruth

__all__ = ["RuntimeSnapshot", "TickStats", "TickTimer"]


@dataclass(frozen=True)
class TickStats:
    """Timing of the loop over the recent ticks, s."""

    ticks: int
    compute_last: float
    compute_p99: float
    jitter_p99: float
    overruns: int
    stall_max: float = 0.0  # how late the latest tick so far came, s
    setpoint_gap_max: float = 0.0  # longest time between two setpoint rounds (loop's clock), s


@dataclass(frozen=True, eq=False)
class RuntimeSnapshot:
    """The state of one tick, for the UI and the metrics (immutable; latest wins)."""

    fleet: FleetState
    phase: Phase
    operator: OperatorSnapshot
    demand: MotionDemand  # what the guidance used (frozen motion: zero sticks)
    accel_cmd: np.ndarray  # (n, 2) NED m/s^2 sent this tick (zeros when not streaming)
    distance_errors: np.ndarray  # (m,) m, NaN while unknown
    safety: SafetyVerdict
    compute_time: float  # s of wall time, this tick (Runtime.stats() has the percentiles)
    compute_cpu: float = 0.0  # s of this thread's CPU time, this tick (excludes preemption)
    events: tuple[Event, ...] = field(default=())
    truth: SimTruth | None = None  # simulation only: the ground truth of this tick
    moving: bool = False  # the operator's motion was flown this tick (not frozen or held)
    fence: FenceVerdict | None = None  # what the geofence did (None: not applied)
    recovery: str = ""  # vehicles waiting to be re-engaged, and when (empty: none)
    shape: Deformation = Deformation.NONE  # what a team deformed beyond the bound does
    prearm: tuple[str, ...] = ()  # ready: the checks before arming failing now (Prearm.watch)


class TickTimer:
    """How long the recent ticks computed, how late they started, how many overran."""

    def __init__(self) -> None:
        self._compute: collections.deque[float] = collections.deque(maxlen=400)
        self._jitter: collections.deque[float] = collections.deque(maxlen=400)
        self.overruns = 0
        self.ticks = 0
        self.stall_max = 0.0

    def started(self, late: float) -> None:
        """A tick started ``late`` s after it was due."""
        self.stall_max = max(self.stall_max, late)
        self._jitter.append(late)

    def computed(self, seconds: float) -> None:
        """A tick took ``seconds`` of wall time."""
        self._compute.append(seconds)
        self.ticks += 1

    def stats(self, *, setpoint_gap_max: float) -> TickStats:
        """Over the recent ticks, with the setpoint stream's longest gap."""
        comp = np.array(self._compute) if self._compute else np.zeros(1)
        jit = np.array(self._jitter) if self._jitter else np.zeros(1)
        return TickStats(ticks=self.ticks, compute_last=float(comp[-1]),
                         compute_p99=float(np.percentile(comp, 99)),
                         jitter_p99=float(np.percentile(jit, 99)), overruns=self.overruns,
                         stall_max=self.stall_max, setpoint_gap_max=setpoint_gap_max)
