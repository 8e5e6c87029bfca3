"""Ctrl-C and SIGTERM stop a command, whatever started it."""

from __future__ import annotations

import signal
import threading
from types import FrameType

__all__ = ["stop_on_signals"]


def _raise_interrupt(_signum: int, _frame: FrameType | None) -> None:
    raise KeyboardInterrupt


def stop_on_signals() -> None:
    """SIGINT (Ctrl-C) and SIGTERM raise KeyboardInterrupt in the main thread.

    Why: a shell script that starts ``gcs demo &`` (any command in the background of a
    non-interactive shell) starts it with SIGINT ignored, and Python leaves an ignored
    SIGINT ignored: the Ctrl-C a supervisor or a test sent did nothing, and the page and
    its simulator ran on. SIGTERM is treated like Ctrl-C, so a terminated command still
    stops what it started (its simulator, its recording) on its way out. Does nothing
    outside the main thread, where Python cannot set handlers.
    """
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, _raise_interrupt)
