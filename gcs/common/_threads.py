"""Stopping a thread and saying so when it will not stop.

Why: every ``close()`` waits a bounded time for its worker thread, so a stuck
thread (a driver call that never returns, a socket read the OS does not wake)
cannot hang the GCS on exit. A thread that outlives the wait is left running and
named in one warning, so whoever reads the log knows which part did not stop.
"""

from __future__ import annotations

import logging
import threading

__all__ = ["join_thread"]

_log = logging.getLogger(__name__)


def join_thread(thread: threading.Thread | None, timeout_s: float, *, what: str) -> bool:
    """Wait up to ``timeout_s`` for ``thread`` to end; True if it has (or never ran).

    A thread still alive after the wait is reported in one warning naming
    ``what`` and the thread, and left running (it is a daemon, or the process
    is on its way out). The calling thread itself is never joined.
    """
    if thread is None or thread is threading.current_thread() or not thread.is_alive():
        return True
    thread.join(timeout=timeout_s)
    if thread.is_alive():
        _log.warning("%s (thread %r) did not stop within %g s; left running",
                     what, thread.name, timeout_s)
        return False
    return True
