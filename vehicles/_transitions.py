"""Mode entry actions, shared by the kernel (timeouts, touchdown) and by commands.

Each function switches vehicle ``i`` into a mode and records what that mode
needs (where to hold, where home is). They are numba functions so the kernel
calls them at 512 Hz and :class:`vehicles.Autopilot` calls the same
code when a command arrives.
"""

from __future__ import annotations

from gcs.common import kernel
from gcs.wire import SimMode
from vehicles._quaternion import quat_to_euler
from vehicles._state import AutopilotState

__all__ = ["enter_armed_hold", "enter_disarmed", "enter_hold", "enter_land", "enter_offboard",
           "enter_takeoff"]

_DISARMED = int(SimMode.DISARMED)
_TAKEOFF = int(SimMode.TAKEOFF)
_OFFBOARD = int(SimMode.OFFBOARD)
_HOLD = int(SimMode.HOLD)
_LAND = int(SimMode.LAND)


@kernel()
def enter_hold(s: AutopilotState, i: int) -> None:
    """HOLD at the current position estimate, starting the hold timer now."""
    s.mode[i] = _HOLD
    for k in range(3):
        s.p_hold[i, k] = s.p_est[i, k]
    s.hold_start[i] = s.t[0]


@kernel()
def enter_armed_hold(s: AutopilotState, i: int) -> None:
    """Arm on the ground: home is here, heading is kept, idle in HOLD."""
    enter_hold(s, i)
    s.z_home[i] = s.p_est[i, 2]
    s.yaw_hold[i] = quat_to_euler(s.q_est[i, 0], s.q_est[i, 1], s.q_est[i, 2], s.q_est[i, 3])[2]


@kernel()
def enter_takeoff(s: AutopilotState, i: int, altitude: float) -> None:
    """Climb to ``altitude`` m above home, holding the current horizontal position."""
    s.mode[i] = _TAKEOFF
    for k in range(3):
        s.p_hold[i, k] = s.p_est[i, k]
    s.z_target[i] = s.z_home[i] - altitude
    s.z_ref[i] = s.p_est[i, 2]


@kernel()
def enter_land(s: AutopilotState, i: int) -> None:
    """Descend at the landing speed above the current horizontal position."""
    s.mode[i] = _LAND
    for k in range(3):
        s.p_hold[i, k] = s.p_est[i, k]
    s.touchdown_timer[i] = 0.0


@kernel()
def enter_offboard(s: AutopilotState, i: int) -> None:
    """Track the external setpoints."""
    s.mode[i] = _OFFBOARD


@kernel()
def enter_disarmed(s: AutopilotState, i: int) -> None:
    """Stop the rotors."""
    s.mode[i] = _DISARMED
    for k in range(4):
        s.rotor_speed_cmd[i, k] = 0.0
        s.rotor_speed_model[i, k] = 0.0
