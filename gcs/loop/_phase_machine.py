"""The flight phase as state: one value, moved by the loop and the action threads alike.

Which action leads where is :func:`gcs.loop._phases.next_phase`; this holds the
current phase, announces each change as an event, and starts the abort's hold.
"""

from __future__ import annotations

import threading

from gcs.loop._events import EventLog
from gcs.loop._phases import Action, Phase, next_phase

__all__ = ["PhaseMachine"]


class PhaseMachine:
    """The team's phase; thread-safe."""

    def __init__(self, events: EventLog) -> None:
        self._events = events
        self._lock = threading.Lock()
        self._phase = Phase.CONNECT
        self.abort_at: float | None = None
        """When the abort's hold began (None: not aborting, or its landing began)."""

    @property
    def phase(self) -> Phase:
        with self._lock:
            return self._phase

    def target(self, action: Action) -> Phase:
        """Where ``action`` leads from the phase now; PhaseError if it may not be taken."""
        with self._lock:
            return next_phase(self._phase, action)

    def set(self, phase: Phase) -> None:
        """Move to ``phase``, announced once (no event if it is the phase already)."""
        with self._lock:
            if phase is self._phase:
                return
            self._phase = phase
        self.announce(phase)

    def start_abort(self, now: float) -> Phase | None:
        """Enter the abort's hold at ``now``: the phase entered, or None where the abort
        changes nothing (aborting or landing already). PhaseError where none may start.

        The check and the hold's start are one step under the lock: aborts arrive
        from several threads at once (every viewer, the gamepad, the safety rules),
        and a repeated one must not restart the hold.
        """
        with self._lock:
            target = next_phase(self._phase, Action.ABORT)
            if target is self._phase:
                return None
            self._phase, self.abort_at = target, now
        return target

    def announce(self, phase: Phase) -> None:
        """The event of a phase change (what the page's events and the tests look for)."""
        self._events.add("info", f"phase: {phase.text}")
