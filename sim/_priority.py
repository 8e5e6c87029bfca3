"""A sim's stepping thread in the background while it keeps up with wall time (opt-in).

Why: the sim often shares its machine with the GCS (``gcs demo``, a bench).
Every few milliseconds it steps physics and encodes telemetry for a fraction
of a millisecond; at normal priority a GCS loop or MAVLink receive thread that
wakes meanwhile may wait for that burst, which on a two-core machine lengthens
the tail of a zenoh round trip between two other processes several times
(figures: docs/performance.md, bench/link_latency.py). At Linux's
``SCHED_IDLE`` the kernel counts the sim's core as idle: a waking normal thread
is placed there and preempts it at once (a shorter time slice or nice 19 does
not help).

The price is that a saturated machine gives the thread almost nothing, and a
starved sim would freeze the team's telemetry. So a watchdog at normal
priority checks often whether the stepping thread has fallen behind its
wall-time schedule and lifts it to normal priority; the stepping thread goes
back to the background once it is ahead again and a second has passed
(:meth:`BackgroundStepping.keeping_up`), since on a machine that stays
saturated going back at once would starve it again at every chunk. The
watchdog is a small process of its own (:mod:`sim._lifter`): a thread would
need the GIL, which the starved loop may hold, and cannot keep a paced host
at real time on a saturated machine; the process keeps it at the pace the same
host keeps at normal priority (figures: docs/performance.md,
tests/test_sim_priority.py). It is an option (``python -m sim --background``),
not the default: it costs a process.

Lifting needs the right to raise a thread's priority (root, CAP_SYS_NICE, or
an RLIMIT_NICE of 20); without it the thread could not come back, so it stays
at normal priority, as it does where the policy does not exist (not Linux).
"""

from __future__ import annotations

import math
import mmap
import os
import subprocess
import sys
import tempfile
import threading
import time

from sim import _lifter

__all__ = ["STAY_LIFTED_S", "WATCH_PERIOD_S", "BackgroundStepping", "can_lift",
           "set_background"]

WATCH_PERIOD_S = 0.01
"""How often the watchdog looks whether the stepping thread fell behind, s."""

STAY_LIFTED_S = 1.0
"""A lifted stepping thread stays at normal priority at least this long, s."""

_START_TIMEOUT_S = 5.0
"""Longest wait for the watchdog process to say it watches, s."""

_SHARED_DIR = "/dev/shm"
"""Where the numbers shared with the watchdog are mapped from (memory, where it exists)."""

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


def _policy(tid: int) -> int | None:
    """Thread ``tid``'s scheduling policy (0: the calling thread); None where unknown."""
    try:
        return os.sched_getscheduler(tid)
    except (AttributeError, OSError):  # not Linux, or a thread that exited
        return None


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

    The stepping thread says when the chunk it steps is due (:meth:`set_due`); a
    watchdog process (:mod:`sim._lifter`) lifts it to normal priority once that is
    more than ``lag_s`` past, and it goes back to the background from
    :meth:`keeping_up`.
    """

    def __init__(self, *, lag_s: float, watch_period_s: float = WATCH_PERIOD_S,
                 stay_lifted_s: float = STAY_LIFTED_S) -> None:
        self._lag = lag_s
        self._period = watch_period_s
        self._stay_lifted = stay_lifted_s
        self._tid: int | None = None
        self._shared: mmap.mmap | None = None
        self._watchdog: subprocess.Popen[bytes] | None = None
        self._lifts = 0

    @property
    def background(self) -> bool:
        """Whether the stepping thread runs in the background now."""
        return self._shared is not None and self._tid is not None \
            and _policy(self._tid) == _IDLE

    @property
    def lifts(self) -> int:
        """How often the watchdog lifted the stepping thread (a starved sim)."""
        if self._shared is not None:
            self._lifts = int(_lifter.read(self._shared)[_lifter.LIFTS])
        return self._lifts

    def start(self) -> bool:
        """From the stepping thread: go to the background and start watching; False (and
        nothing changed) where the thread could not be lifted again or no watchdog
        started."""
        if not can_lift():
            return False
        tid = threading.get_native_id()
        with tempfile.NamedTemporaryFile(dir=_SHARED_DIR if os.path.isdir(_SHARED_DIR)
                                         else None, prefix="sim-lifter-") as f:
            f.write(_lifter.LAYOUT.pack(math.inf, self._lag, self._period, -math.inf, 0, 0, 0))
            f.flush()
            shared = mmap.mmap(f.fileno(), _lifter.LAYOUT.size)
            watchdog = subprocess.Popen([sys.executable, "-I", "-S", _lifter.__file__, f.name,
                                         str(tid)], stdin=subprocess.DEVNULL)
            deadline = time.monotonic() + _START_TIMEOUT_S
            while not _lifter.read(shared)[_lifter.READY]:
                if watchdog.poll() is not None or time.monotonic() > deadline:
                    watchdog.kill()
                    watchdog.wait()
                    shared.close()
                    return False
                time.sleep(0.005)
        self._tid, self._shared, self._watchdog = tid, shared, watchdog
        return set_background(True)

    def set_due(self, due: float | None) -> None:
        """From the stepping thread: the chunk it steps is due at monotonic time ``due``
        (None: no wall-time schedule, never late)."""
        if self._shared is not None:
            _lifter.write(self._shared, _lifter.DUE, math.inf if due is None else due)

    def keeping_up(self) -> None:
        """From the stepping thread, when it is ahead of schedule: back to the background
        (once :data:`STAY_LIFTED_S` passed since it was lifted)."""
        shared = self._shared
        if shared is None:
            return
        values = _lifter.read(shared)
        if values[_lifter.STOP] or _policy(0) == _IDLE \
                or time.monotonic() - float(values[_lifter.LIFTED_AT]) < self._stay_lifted:
            return
        set_background(True)

    def close(self) -> None:
        """Stop watching and leave the stepping thread at normal priority; idempotent."""
        shared, watchdog = self._shared, self._watchdog
        if shared is None or watchdog is None:
            return
        _lifter.write(shared, _lifter.STOP, 1)
        try:
            watchdog.wait(timeout=1.0)
        except subprocess.TimeoutExpired:
            watchdog.kill()
            watchdog.wait()
        self._lifts = int(_lifter.read(shared)[_lifter.LIFTS])
        if self._tid is not None and _policy(self._tid) == _IDLE:
            set_background(False, self._tid)
        self._shared = self._watchdog = None
        shared.close()
