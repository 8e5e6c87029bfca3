"""The PX4 face of one vehicle's modes: the mode its HEARTBEAT reports, and what a PX4 mode
request does.

Why: ground stations name a vehicle's modes from its autopilot type, so the
simulated vehicle reports PX4's (:data:`gcs.wire.SIM_PX4_MODES`) while its
kernel keeps its own five (:class:`gcs.wire.SimMode`). One mode of the kernel,
HOLD, is what three PX4 modes do without sticks: AUTO.LOITER (Hold), POSCTL
and ALTCTL. A vehicle asked for POSCTL reports POSCTL for as long as that hold
lasts, and AUTO.LOITER again for any hold it enters on its own (after a
take-off, a lost setpoint stream), as PX4 would.
"""

from __future__ import annotations

import math

from gcs.wire import (
    SIM_PX4_MODES,
    Px4AutoSubMode,
    Px4MainMode,
    SimMode,
    px4_custom_mode,
    sim_mode_for_px4,
)
from vehicles._autopilot import Autopilot

__all__ = ["Px4Modes"]

_HOLD = int(SimMode.HOLD)


class Px4Modes:
    """Vehicle ``index`` of ``autopilot`` as PX4 modes; loop thread only."""

    def __init__(self, autopilot: Autopilot, index: int) -> None:
        self.autopilot = autopilot
        self.index = index
        self._hold_as = 0
        """custom_mode of the hold asked for last (0: none)."""
        self._hold_start = math.nan
        """The kernel's hold start time of that hold: a later hold is another one."""

    @property
    def mode(self) -> SimMode:
        """The kernel's mode."""
        return self.autopilot.mode(self.index)

    def custom_mode(self) -> int:
        """PX4 ``custom_mode`` to report now."""
        state = self.autopilot.state
        if (self._hold_as and state.mode[self.index] == _HOLD
                and state.hold_start[self.index] == self._hold_start):
            return self._hold_as
        return SIM_PX4_MODES[self.mode]

    def held_as(self, main: int, sub: int) -> None:
        """The hold just entered was asked for as PX4 mode (main, sub): report that one."""
        if sim_mode_for_px4(main, sub) is not SimMode.HOLD:
            raise ValueError(f"PX4 mode {main}.{sub} is no hold")
        custom = (px4_custom_mode(Px4MainMode.AUTO, Px4AutoSubMode.LOITER)
                  if main == Px4MainMode.AUTO else px4_custom_mode(Px4MainMode(main)))
        self._hold_as = custom
        self._hold_start = float(self.autopilot.state.hold_start[self.index])
