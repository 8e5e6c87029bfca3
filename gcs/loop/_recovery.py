"""Recovery after a setpoint gap: when vehicles that dropped to hold are flown again.

A vehicle whose setpoints stop for its timeout (0.5 s on PX4 and on our
simulated autopilot) leaves offboard for a hold of its own. On a busy laptop
or a radio that loses a second, that happens to a healthy team in the middle
of a flight; freezing the motion until someone notices would end flights that
have nothing wrong left. So once every link has been fresh for
``safety.recover_after`` seconds, nothing holds the team (no deformation
beyond the safe bound, no vehicle coming down), the vehicles out of their
streaming mode are switched back (the same RESUME an operator presses), and
the motion resumes. With ``safety.recovery: operator`` the GCS only says
which vehicles wait and lets the operator resume.

Only a vehicle that left its mode around a gap (:meth:`Recovery.note_gap`: a
loop stall, a pause in the setpoint stream, stale telemetry) is re-engaged by
itself: one that left it while everything flowed was switched by someone (a
pilot's mode switch, another ground station), and the GCS does not overrule
them; that one waits for the operator's resume.
"""

from __future__ import annotations

import math

__all__ = ["GAP_WINDOW_S", "Recovery"]

GAP_WINDOW_S = 3.0
"""A vehicle seen out of its mode at most this long after a gap left it because of the gap, s."""


class Recovery:
    """Decides, tick by tick, when to re-engage the vehicles that left their streaming mode.

    Args:
        automatic: re-engage by itself (``safety.recovery: auto``).
        settle: every link fresh this long first, s (``safety.recover_after``).
    """

    def __init__(self, *, automatic: bool, settle: float) -> None:
        self.automatic = automatic
        self.settle = settle
        self._fresh_since: float | None = None
        self._last_try = -math.inf
        self._gap_at = -math.inf
        self._out_since: dict[int, float] = {}
        self._after_gap: set[int] = set()
        self.waiting: tuple[int, ...] = ()
        """Vehicles out of their streaming mode that recovery (or the operator) would resume."""
        self.attempts = 0
        """Re-engagements started so far."""

    def note_gap(self, now: float) -> None:
        """Setpoints may have stopped reaching the team around ``now`` (the loop's time)."""
        self._gap_at = now

    @property
    def after_gap(self) -> tuple[int, ...]:
        """The waiting vehicles that left their mode around a gap (re-engaged by themselves)."""
        return tuple(v for v in self.waiting if v in self._after_gap)

    def update(self, now: float, *, out: tuple[int, ...], healthy: bool) -> bool:
        """This tick's state; True when the vehicles :attr:`after_gap` should be re-engaged now.

        Args:
            now: the loop's time, s.
            out: vehicles out of their streaming mode while flying, not coming down.
            healthy: every link fresh, the team placed and not held for deformation.
        """
        for vid in out:
            if vid not in self._out_since:
                self._out_since[vid] = now
                if now - self._gap_at <= GAP_WINDOW_S:
                    self._after_gap.add(vid)
        for vid in set(self._out_since) - set(out):
            del self._out_since[vid]
            self._after_gap.discard(vid)
        self.waiting = out
        if not out or not healthy:
            self._fresh_since = None
            return False
        if self._fresh_since is None:
            self._fresh_since = now
        if not self.automatic or not self.after_gap:
            return False
        if now - self._fresh_since < self.settle or now - self._last_try < self.settle:
            return False
        self._last_try = now
        self.attempts += 1
        return True

    def status(self, now: float) -> str:
        """One line for the operator while vehicles wait; empty otherwise."""
        if not self.waiting:
            return ""
        ids = ", ".join(str(v) for v in self.waiting)
        if not self.automatic or not self.after_gap:
            return f"vehicles {ids} out of the streaming mode: press Resume to fly them again"
        ids = ", ".join(str(v) for v in self.after_gap)
        if self._fresh_since is None:
            return f"vehicles {ids} out of the streaming mode: waiting for every link"
        left = max(self.settle - (now - self._fresh_since), 0.0)
        return f"vehicles {ids} out of the streaming mode: re-engaging in {left:.1f} s"
