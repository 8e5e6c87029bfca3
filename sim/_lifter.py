"""The watchdog process of :mod:`sim._priority`: lifts a starved stepping thread.

Why a process: a watchdog thread needs the GIL, which the stepping thread may
hold while the kernel starves it in the background, so on a machine
oversubscribed by other processes the thread meant to rescue it would wait for
it, and the sim would all but stop (figures: docs/performance.md). This process
has an interpreter of its own and imports nothing but the standard library (so
it starts quickly): ``python sim/_lifter.py SHARED TID``.

It shares a few numbers with the stepping process through a small file
mapped into both (:data:`LAYOUT`): when the chunk the stepping thread steps
is overdue by more than ``lag`` and the thread is in the background, it sets
the thread's policy back to normal (allowed to a process that may raise
priorities, as the stepping one checked) and says so there. Whether the
thread is in the background it asks the kernel, not a shared flag: a flag
written beside the policy change would leave a window where the thread
starves in the background with the flag still saying it is not.
"""

from __future__ import annotations

import mmap
import os
import struct
import sys
import time

LAYOUT = struct.Struct("<ddddqqq")
"""due (monotonic s, inf when not paced), lag (s), period (s), lifted_at (monotonic s),
lifts, stop (0/1), ready (0/1)."""
DUE, LAG, PERIOD, LIFTED_AT, LIFTS, STOP, READY = range(7)


def read(shared: mmap.mmap) -> list[float | int]:
    """The shared numbers, in :data:`LAYOUT`'s order."""
    return list(LAYOUT.unpack_from(shared, 0))


def write(shared: mmap.mmap, field: int, value: float | int) -> None:
    """One shared number (each is written whole: 8 aligned bytes)."""
    fmt = "<d" if field <= LIFTED_AT else "<q"
    struct.pack_into(fmt, shared, 8 * field, value)


def watch(path: str, tid: int) -> None:
    """Until told to stop or the stepping process is gone."""
    parent = os.getppid()
    with open(path, "r+b") as f:
        shared = mmap.mmap(f.fileno(), LAYOUT.size)
    write(shared, READY, 1)
    while True:
        values = read(shared)
        time.sleep(float(values[PERIOD]))
        values = read(shared)
        if values[STOP] or os.getppid() != parent:
            return
        now = time.monotonic()
        if now - float(values[DUE]) <= float(values[LAG]):
            continue
        try:
            if os.sched_getscheduler(tid) != os.SCHED_IDLE:
                continue
            write(shared, LIFTED_AT, now)  # before the lift: the thread reads it once lifted
            os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))
        except OSError:  # the thread is gone
            return
        write(shared, LIFTS, int(values[LIFTS]) + 1)


if __name__ == "__main__":
    watch(sys.argv[1], int(sys.argv[2]))
