"""Ctrl-C and SIGTERM stop a command, whatever started it; a child dies with its parent."""

from __future__ import annotations

import ctypes
import signal
import sys
import threading
from types import FrameType

__all__ = ["die_with_parent", "stop_on_signals"]

_PR_SET_PDEATHSIG = 1


def die_with_parent() -> None:
    """In a child process: get SIGTERM when the parent dies, even by SIGKILL (Linux; elsewhere
    nothing), so no simulator is left flying headless when its GCS is gone."""
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)


def _raise_interrupt(_signum: int, _frame: FrameType | None) -> None:
    raise KeyboardInterrupt


def stop_on_signals() -> None:
    """SIGINT (Ctrl-C) and SIGTERM raise KeyboardInterrupt in the main thread.

    Why: a shell script that starts ``gcs demo &`` (any command in the background of a
    non-interactive shell) starts it with SIGINT ignored, and Python leaves an ignored
    SIGINT ignored: a Ctrl-C from a supervisor or a test would do nothing, and the page
    and its simulator would run on. SIGTERM is treated like Ctrl-C, so a terminated command still
    stops what it started (its simulator, its recording) on its way out. Does nothing
    outside the main thread, where Python cannot set handlers.
    """
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, _raise_interrupt)
