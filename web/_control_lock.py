"""Who may steer the team: at most one viewer at a time.

Every browser sees the flight; only the holder's sticks, keys and buttons
reach the operator command (checked on the server, not just greyed out in
the page). Taking control from another viewer is allowed and immediate, as a
second pilot taking the sticks; the previous holder is told and becomes a
viewer. The abort button is the one exception: any viewer may abort.
"""

from __future__ import annotations

import threading

__all__ = ["ControlLock"]


class ControlLock:
    """The id of the viewer holding control, or None; thread-safe."""

    def __init__(self) -> None:
        self._holder: int | None = None
        self._lock = threading.Lock()

    @property
    def holder(self) -> int | None:
        with self._lock:
            return self._holder

    def holds(self, client_id: int | None) -> bool:
        """True if ``client_id`` holds control (None never does)."""
        with self._lock:
            return client_id is not None and self._holder == client_id

    def take(self, client_id: int) -> int | None:
        """Give control to ``client_id``; returns who held it before (None: nobody)."""
        with self._lock:
            previous, self._holder = self._holder, client_id
            return previous

    def release(self, client_id: int) -> bool:
        """Drop control if ``client_id`` holds it; True if it did."""
        with self._lock:
            if self._holder != client_id:
                return False
            self._holder = None
            return True
