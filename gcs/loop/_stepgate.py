"""In lockstep with the simulator, helper threads act only at ticks.

Why: in lockstep the sim stands still at the tick's time until the GCS acks
the tick. A command sent, or a stick moved, while it stands still takes effect
at that sim time whatever the machine's load; one sent a few milliseconds
later lands wherever the sim has run to by then. So that ``gcs fly`` gives the
same flight on every run, the threads that act besides the loop (phase
actions and the per-vehicle steps they run, a scripted scenario) register
here as *participants*. A participant runs only while the loop holds a tick's
*window* open, before the tick is acked, and parks (:meth:`StepGate.pause`)
whenever it must wait for sim time to pass: the window closes once every
participant is parked or done.

Disabled (the wall clock, real vehicles), nothing is gated: :meth:`pause`
answers False and callers wait their own way.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Executor, Future
from contextlib import contextmanager
from typing import TypeVar

from gcs.loop._clock import Clock

__all__ = ["HOLD_CAP_S", "GatedClock", "StepGate"]

T = TypeVar("T")

HOLD_CAP_S = 10.0
"""Longest wall time a window waits for busy participants before the sim moves on, s."""


class StepGate:
    """Counts participants; the loop opens a window per tick and waits for them to park."""

    def __init__(self, *, enabled: bool, hold_cap_s: float = HOLD_CAP_S) -> None:
        self.enabled = enabled
        self._hold_cap_s = hold_cap_s
        self._cond = threading.Condition()
        self._active = 0  # participants running (or submitted and about to run)
        self._parked = 0  # participants waiting for the next window
        self._window = 0  # windows opened so far
        self._open = False  # the loop is in a window (its thread waits in window())
        self._closed = False
        self._local = threading.local()

    # -- participants ----------------------------------------------------------------------

    @contextmanager
    def participant(self) -> Iterator[None]:
        """Make the calling thread a participant for the ``with`` block."""
        if not self.enabled:
            yield
            return
        with self._cond:
            self._active += 1
        try:
            with self._marked():
                yield
        finally:
            self._leave()

    def submit(self, executor: Executor, fn: Callable[..., T], *args: object) -> Future[T]:
        """Run ``fn(*args)`` on ``executor`` as a participant, counted from now on.

        Submitted in a window (an operator's request, a scenario step), the work is
        counted at once, so the window cannot close before it starts: it runs in
        that window. Submitted between windows (by the loop's own tick: a recovery's
        resume, the landing after an abort's hold), it is parked until the next
        window opens, as a participant that paused: started at once, it would race
        the rest of the tick (a resume's hold setpoint going before or after the
        tick's setpoints, whichever thread is first), and two runs of one seed would
        differ.
        """
        if not self.enabled:
            return executor.submit(fn, *args)
        with self._cond:
            wait_for = None if self._open else self._window  # the window it must wait past
            if wait_for is None:
                self._active += 1
            else:
                self._parked += 1
        try:
            return executor.submit(self._run, None, fn, *args, wait_for=wait_for)
        except BaseException:
            with self._cond:
                if wait_for is None or self._window != wait_for:  # a window made it active
                    self._active -= 1
                else:
                    self._parked -= 1
                self._cond.notify_all()
            raise

    def map(self, executor: Executor, fn: Callable[[T], object],
            items: Sequence[T]) -> list[BaseException | None]:
        """``fn(item)`` for every item in parallel; blocks; each item's exception or None.

        A participant calling this is not counted while its items run; the last item
        to finish hands the count back to it in the same step, so no window closes
        between the last item and the caller going on.
        """
        if not (self.enabled and self._is_participant()):
            futures = [executor.submit(fn, item) for item in items]
        else:
            group = _Group(len(items))
            with self._cond:
                self._active += len(items) - 1 if items else 0  # the caller's count goes too
                if not items:
                    return []
            futures = [executor.submit(self._run, group, fn, item) for item in items]
        return [fut.exception() for fut in futures]

    def pause(self) -> bool:
        """Park until the next window if the calling thread is a participant (True).

        False (gate disabled, or not a participant): nothing was waited for; the
        caller waits its own way.
        """
        if not (self.enabled and self._is_participant()):
            return False
        with self._cond:
            if self._closed:
                return False
            window = self._window
            self._active -= 1
            self._parked += 1
            self._cond.notify_all()
            while self._window == window and not self._closed:
                self._cond.wait()
            if self._closed and self._window == window:  # never moved to active by a window
                self._parked -= 1
                self._active += 1
        return True

    # -- the loop ----------------------------------------------------------------------------

    def window(self) -> bool:
        """Let the parked participants run until all are parked or done; the loop's thread.

        Returns False if some were still busy after the hold cap (the tick goes on).
        """
        if not self.enabled:
            return True
        with self._cond:
            self._window += 1
            self._active += self._parked
            self._parked = 0
            self._open = True
            self._cond.notify_all()
            try:
                return self._cond.wait_for(lambda: self._active <= 0 or self._closed,
                                           self._hold_cap_s)
            finally:
                self._open = False

    def close(self) -> None:
        """Release every parked participant and never wait again."""
        with self._cond:
            self._closed = True
            self._cond.notify_all()

    # -- helpers -------------------------------------------------------------------------------

    def _is_participant(self) -> bool:
        return getattr(self._local, "depth", 0) > 0

    @contextmanager
    def _marked(self) -> Iterator[None]:
        """Mark the calling thread a participant (what :meth:`pause` checks)."""
        self._local.depth = getattr(self._local, "depth", 0) + 1
        try:
            yield
        finally:
            self._local.depth -= 1

    def _run(self, group: _Group | None, fn: Callable[..., T], *args: object,
             wait_for: int | None = None) -> T:
        if wait_for is not None:  # submitted between windows: park until the next one
            with self._cond:
                while self._window == wait_for and not self._closed:
                    self._cond.wait()
                if self._window == wait_for:  # closed before any window took it
                    self._parked -= 1
                    self._active += 1
        try:
            with self._marked():
                return fn(*args)
        finally:
            if group is None:
                self._leave()
            else:
                with self._cond:
                    group.left -= 1
                    if group.left > 0:  # the last one keeps its count for the caller
                        self._active -= 1
                        self._cond.notify_all()

    def _leave(self) -> None:
        with self._cond:
            self._active -= 1
            self._cond.notify_all()


class _Group:
    """Items of one :meth:`StepGate.map` call still running."""

    def __init__(self, n: int) -> None:
        self.left = n


class GatedClock:
    """``clock`` for a participant: :meth:`sleep_until` parks at ticks instead of sleeping."""

    def __init__(self, clock: Clock, gate: StepGate) -> None:
        self._clock = clock
        self._gate = gate

    def now(self) -> float:
        """The wrapped clock's time, s."""
        return self._clock.now()

    def sleep_until(self, t: float) -> None:
        """Park tick after tick until ``t`` (or sleep on the clock when not gated)."""
        while self._clock.now() < t:
            if not self._gate.pause():
                self._clock.sleep_until(t)
                return
