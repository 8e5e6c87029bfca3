"""Joining a running simulator (``gcs fly --connect``): lockstep or not, and whether it is sound.

Why: a simulator started elsewhere with ``--lockstep`` waits for a GCS's first
clock ack, and one started without runs on at its own ``--speed``; the joining
GCS reads which from the simulator's clock samples (a lockstep simulator
appends its counts, :func:`gcs.wire.encode_clock`) before it opens any link,
so it acks when the simulator waits for it and is refused at once, with the
reason, where no flight can be sound:

* a lockstep simulator that names its partner: another GCS acks it (or did),
  and a lockstep simulator follows one GCS (:mod:`gcs.wire._clockwire`);
* a free-running simulator faster than real time: a GCS that does not pace it
  cannot keep up (late ticks, stale telemetry, vehicles falling out of the
  setpoint stream), so it is followed only at up to 1x.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from gcs.common import ConfigError
from gcs.wire import ClockSample

__all__ = ["FREE_PACE_MAX", "JOIN_TIMEOUT_S", "PACE_WINDOW_S", "ClockProbe", "free_pace"]

JOIN_TIMEOUT_S = 10.0
"""Longest wall time a joining GCS waits for the simulator's first clock sample, s (a
waiting lockstep simulator repeats its clock ten times a second)."""

PACE_WINDOW_S = 1.5
"""Wall time over which a free-running simulator's pace is measured, s: several times a slow
link's jitter (a sample held back 0.15 s makes a 0.5 s window read 1.3x real time)."""

FREE_PACE_MAX = 1.2
"""Fastest pace of a free-running simulator a GCS follows, sim s per wall s: real time, with
room for the measurement's jitter."""


class ClockProbe:
    """The first clock samples of a simulator being joined, and the verdict on them.

    Samples are added from zenoh's callback thread (:meth:`add`); :meth:`judge`
    blocks the joining thread until it can say.
    """

    def __init__(self, endpoint: str) -> None:
        self._endpoint = endpoint
        self._cond = threading.Condition()
        self._samples: list[tuple[float, ClockSample]] = []  # (wall time it came, sample)

    def add(self, sample: ClockSample) -> None:
        """A sealed, well-formed clock sample from the simulator (any thread)."""
        with self._cond:
            self._samples.append((time.monotonic(), sample))
            self._cond.notify_all()

    def judge(self, *, timeout: float = JOIN_TIMEOUT_S, window: float = PACE_WINDOW_S) -> bool:
        """Whether the simulator is in lockstep (this GCS then acks it); ConfigError on
        ``--connect`` naming why it cannot be joined."""
        with self._cond:
            if not self._cond.wait_for(lambda: bool(self._samples), timeout):
                raise ConfigError("--connect", "", f"no clock sample sealed with the team key "
                                  f"from a simulator at {self._endpoint} within {timeout:g} s "
                                  f"(is it running there, on this team file and fleet?)")
            wall0, first = self._samples[0]
            if first.truth is not None:
                if first.partner is not None:
                    raise ConfigError("--connect", "", f"the simulator at {self._endpoint} is "
                                      f"in lockstep with another GCS already (at t = "
                                      f"{first.t:.3f} s), and a lockstep simulator follows "
                                      f"one GCS: start a fresh one for this flight")
                return True
            self._cond.wait_for(lambda: self._samples[-1][0] - wall0 >= window, window + 1.0)
            samples = list(self._samples)
        pace = free_pace(np.array([w for w, _ in samples]), np.array([c.t for _, c in samples]))
        if pace > FREE_PACE_MAX:
            raise ConfigError("--connect", "", f"the simulator at {self._endpoint} runs free "
                              f"at {pace:.1f}x real time, faster than a GCS that does not pace "
                              f"it can follow (1x at most): start it with --lockstep to fly "
                              f"faster than real time, or with --speed 1")
        return False


def free_pace(wall: np.ndarray, sim: np.ndarray) -> float:
    """Sim seconds per wall second of clock samples that came at ``wall`` (monotonic s)
    stamped ``sim`` (sim s), judged on the samples the link delayed least.

    Why: every sample comes late by the link's delay, and by more when it was queued or
    resent; the first and last samples alone read that jitter as pace. The least delayed
    sample of the window's first third and of its last third came with about the same
    delay, so their spacing is the simulator's own. A sample's delay is its ``wall`` less
    ``sim`` at the pace, so the pace is found again from the pair it picks, a few times.
    """
    n = len(wall)
    if n < 2 or wall[-1] - wall[0] <= 1e-3:
        return 0.0
    pace = float((sim[-1] - sim[0]) / (wall[-1] - wall[0]))
    third = max(n // 3, 1)
    for _ in range(4):
        delay = wall - sim / max(pace, 1e-6)
        i = int(np.argmin(delay[:third]))
        j = n - third + int(np.argmin(delay[n - third:]))
        if j <= i or wall[j] - wall[i] <= 1e-3:
            break
        pace = float((sim[j] - sim[i]) / (wall[j] - wall[i]))
    return pace
