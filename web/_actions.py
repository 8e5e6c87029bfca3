"""What a viewer can do to the flight, in the loop's time.

The browser writes to the same :class:`~gcs.loop.OperatorCommand` and asks
the same :meth:`~gcs.loop.Runtime.request` as the gamepad and scripted
scenarios; this wrapper only adds the loop's clock and turns a refused phase
action into a message for the viewer instead of an exception in a callback.
"""

from __future__ import annotations

from gcs.loop import Action, Clock, OperatorCommand, PhaseError, Runtime

__all__ = ["OperatorActions"]


class OperatorActions:
    """Operator command and phase actions of one GCS, with its clock."""

    def __init__(self, runtime: Runtime, operator: OperatorCommand, clock: Clock) -> None:
        self.runtime = runtime
        self.operator = operator
        self.clock = clock

    def request(self, action: Action) -> str | None:
        """Start a phase action; the reason as text if the phase does not allow it."""
        try:
            self.runtime.request(action)
        except PhaseError as exc:
            return str(exc)
        return None

    def set_sticks(self, forward: float, right: float, rotate: float, *, source: str) -> None:
        self.operator.set_sticks(forward, right, rotate, now=self.clock.now(), source=source)

    def release(self, *, source: str) -> None:
        """Centre the sticks (a viewer let go of control or left)."""
        self.operator.release(now=self.clock.now(), source=source)

    def step_scale(self, steps: int) -> float:
        return self.operator.step_scale(steps)

    def step_altitude(self, steps: int) -> float:
        return self.operator.step_altitude(steps, now=self.clock.now())

    def set_guidance(self, on: bool) -> None:
        self.operator.set_guidance(on)
