"""A sim's stepping thread in the background while it keeps up with wall time (opt-in).

Why: the sim often shares its machine with the GCS (``gcs demo``, a bench).
Every few milliseconds it steps physics and encodes telemetry for a fraction
of a millisecond; at normal priority a GCS loop or MAVLink receive thread that
wakes meanwhile may wait for that burst, which on a two-core machine tripled
the p99 of a zenoh round trip between two other processes (0.4 ms to 1.3 ms).
At Linux's ``SCHED_IDLE`` the kernel counts the sim's core as idle: a waking
normal thread is placed there and preempts it at once (a shorter time slice
or nice 19 did not help; renice was tried).

The price is that a saturated machine gives the thread almost nothing, and a
starved sim would freeze the team's telemetry. So a watchdog thread at normal
priority checks often whether the stepping thread has fallen behind its
wall-time schedule and lifts it to normal priority; the stepping thread goes
back to the background once it is ahead again and a second has passed
(:meth:`BackgroundStepping.keeping_up`), since on a machine that stays
saturated going back at once would starve it again at every chunk. The
watchdog is Python too and needs the GIL, which the starved loop may hold, so
with every core saturated a paced host keeps 55-70 % of real time (2-4 %
without the watchdog, 100 % at normal priority): the reason this is an
option (``python -m sim --background``) and not the default.

Lifting needs the right to raise a thread's priority (root, CAP_SYS_NICE, or
an RLIMIT_NICE of 20); without it the thread could not come back, so it stays
at normal priority, as it does where the policy does not exist (not Linux).
"""

from __future__ import annotations

import math
import os
import threading
import time
from collections.abc import Callable

from gcs.common import join_thread

__all__ = ["STAY_LIFTED_S", "WATCH_PERIOD_S", "BackgroundStepping", "can_lift",
           "set_background"]

WATCH_PERIOD_S = 0.01
"""How often the watchdog looks whether the stepping thread fell behind, s."""

STAY_LIFTED_S = 1.0
"""A lifted stepping thread stays at normal priority at least this long, s."""

_IDLE = getattr(os, "SCHED_IDLE", None)
_OTHER = getattr(os, "SCHED_OTHER", None)


def set_background(background: bool, tid: int = 0) -> bool:
    """Put thread ``tid`` (0: the calling thread) in the background or back to normal.

    Returns False where the platform has no such policy or refuses the change.
    """
    if _IDLE is None or _OTHER is None or not hasattr(os, "sched_setscheduler"):
        return False
    try:
        os.sched_setscheduler(tid, _IDLE if background else _OTHER, os.sched_param(0))
    except OSError:  # a thread that exited, or a sandbox that forbids it
        return False
    return True


def can_lift() -> bool:
    """Whether a thread put in the background may return to normal priority here.

    Tried on a throwaway thread, which may stay in the background for good.
    """
    result: list[bool] = []

    def probe() -> None:
        result.append(set_background(True) and set_background(False))

    thread = threading.Thread(target=probe, name="sim-priority-probe", daemon=True)
    thread.start()
    thread.join()
    return bool(result and result[0])


class BackgroundStepping:
    """Background priority for the thread that calls :meth:`start`, lifted while it lags.

    ``behind()`` (called on the watchdog thread) says whether the stepping
    thread is late against its schedule; it must be cheap and thread-safe.
    """

    def __init__(self, behind: Callable[[], bool], *,
                 watch_period_s: float = WATCH_PERIOD_S,
                 stay_lifted_s: float = STAY_LIFTED_S) -> None:
        self._behind = behind
        self._period = watch_period_s
        self._stay_lifted = stay_lifted_s
        self._lifted_at = -math.inf
        self._lock = threading.Lock()
        self._tid: int | None = None
        self._background = False
        self.lifts = 0
        """How often the watchdog lifted the stepping thread (a starved sim)."""
        self._stop = threading.Event()
        self._watchdog: threading.Thread | None = None

    @property
    def background(self) -> bool:
        """Whether the stepping thread runs in the background now."""
        return self._background

    def start(self) -> bool:
        """From the stepping thread: go to the background and start watching; False (and
        nothing changed) where the thread could not be lifted again."""
        if not can_lift():
            return False
        # the watchdog first, so it does not inherit the background policy
        self._watchdog = threading.Thread(target=self._watch, name="sim-priority", daemon=True)
        self._tid = threading.get_native_id()
        self._background = set_background(True)
        self._watchdog.start()
        return self._background

    def keeping_up(self) -> None:
        """From the stepping thread, when it is ahead of schedule: back to the background
        (once :data:`STAY_LIFTED_S` passed since it was lifted)."""
        if self._tid is None or self._background \
                or time.monotonic() - self._lifted_at < self._stay_lifted:
            return
        with self._lock:
            if not self._stop.is_set() and set_background(True):
                self._background = True

    def close(self) -> None:
        """Stop watching and leave the stepping thread at normal priority; idempotent."""
        self._stop.set()
        join_thread(self._watchdog, 1.0, what="the background-stepping watchdog")
        with self._lock:
            if self._tid is not None and self._background:
                set_background(False, self._tid)
                self._background = False

    def _watch(self) -> None:
        while not self._stop.wait(self._period):
            if not self._background or not self._behind():
                continue
            with self._lock:
                if self._background and not self._stop.is_set():
                    assert self._tid is not None
                    if set_background(False, self._tid):
                        self._background = False
                        self._lifted_at = time.monotonic()
                        self.lifts += 1
