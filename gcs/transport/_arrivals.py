"""Counts what arrived per source, so a receiver can wait for what a sender says it sent.

Why: a lockstep sim's clock sample announces how many payloads each vehicle,
and how many ground-truth samples the sim, have been published so far
(:mod:`gcs.wire._clockwire`). The clock travels on its own priority and
callback thread and can overtake them; waiting here until the announced
counts have arrived (and been handled) makes the GCS's tick at a given sim
time see the same data on every run.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable, Mapping
from typing import TypeVar

__all__ = ["Arrivals"]

_K = TypeVar("_K", bound=Hashable)

_WRAP = 2**32
"""Counts travel as uint32: compared modulo 2^32."""


class Arrivals:
    """Thread-safe arrival counters per source, and a wait for announced counts."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._arrived: dict[Hashable, int] = {}
        self._missed: dict[Hashable, int] = {}  # announced but never arrived (written off)
        self._waiting = 0

    def arrived(self, source: Hashable) -> None:
        """Count one arrival from ``source`` (call it once the arrival was handled)."""
        with self._cond:
            self._arrived[source] = self._arrived.get(source, 0) + 1
            if self._waiting:
                self._cond.notify_all()

    def wait(self, announced: Mapping[_K, int], timeout_s: float, *,
             only: Callable[[_K], bool] = lambda _source: True) -> bool:
        """Block until every source (those ``only`` accepts) has what ``announced`` says.

        False after ``timeout_s``; what was still missing then (sent before this
        receiver listened, or lost) is written off, so it costs one wait only.
        """
        def lag(source: _K, count: int) -> int:  # still to come, modulo 2^32
            have = self._arrived.get(source, 0) + self._missed.get(source, 0)
            ahead = (count - have) % _WRAP
            return ahead if ahead < _WRAP // 2 else 0  # behind the count: nothing to wait for

        def behind() -> dict[_K, int]:
            return {s: n for s, n in announced.items() if only(s) and lag(s, n)}

        with self._cond:
            self._waiting += 1
            try:
                if self._cond.wait_for(lambda: not behind(), timeout_s):
                    return True
                for s, n in behind().items():
                    self._missed[s] = self._missed.get(s, 0) + lag(s, n)
                return False
            finally:
                self._waiting -= 1
