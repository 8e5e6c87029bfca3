"""Profile of the simulated vehicles (this repository's onboard autopilot).

Sequence, every step acknowledged and confirmed by the HEARTBEAT:

- take-off: arm (MAV_CMD_COMPONENT_ARM_DISARM), then MAV_CMD_NAV_TAKEOFF with
  param7 = climb above the current position, m; the vehicle reports
  :attr:`SimMode.TAKEOFF` and then :attr:`SimMode.HOLD`;
- offboard: one hold setpoint, then MAV_CMD_DO_SET_MODE to
  :attr:`SimMode.OFFBOARD`; setpoints are x/y acceleration + z position;
- land: MAV_CMD_NAV_LAND (:attr:`SimMode.LAND`); disarm once on the ground.
"""

from __future__ import annotations

from gcs.link._profile import ProfileBase, ProfileName
from gcs.wire import SetpointKind, SimMode, mavlink, sim_mode_text

__all__ = ["SimProfile"]


class SimProfile(ProfileBase):
    """Drives a simulated vehicle; see the module docstring for the sequence."""

    expected_autopilots = frozenset({mavlink.MAV_AUTOPILOT_GENERIC})
    streaming_mode = SimMode.OFFBOARD.name
    landing_modes = frozenset({SimMode.LAND.name})
    vertical_is_z = True
    # telemetry_rates_hz stays empty: the simulated vehicles stream position and attitude at
    # 50 Hz of sim time from the start (vehicles._streams), more than the GCS would ask for.

    @property
    def name(self) -> ProfileName:
        """Always :attr:`ProfileName.SIM`."""
        return ProfileName.SIM

    @property
    def setpoint_kind(self) -> SetpointKind:
        """x/y acceleration with z position (the vehicle holds altitude itself)."""
        return SetpointKind.ACCEL_XY_POS_Z

    def _mode_name(self, custom_mode: int) -> str:
        """:class:`SimMode` name."""
        return sim_mode_text(custom_mode)

    def takeoff(self, *, altitude_m: float) -> None:
        """Arm, then NAV_TAKEOFF(param7 = ``altitude_m``); confirmed by TAKEOFF or HOLD."""
        if not altitude_m > 0:
            raise ValueError(f"altitude_m must be positive, got {altitude_m}")
        self.arm()
        self.link.command_long(mavlink.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, 0, 0, 0, altitude_m))
        self._wait_heartbeat(lambda hb: hb.custom_mode in (SimMode.TAKEOFF, SimMode.HOLD),
                             "mode TAKEOFF")

    def start_offboard(self, *, z_ned: float | None = None) -> None:
        """Send a hold setpoint, then switch to OFFBOARD."""
        z = self._position().p_ned[2] if z_ned is None else z_ned
        self.link.send_setpoint(accel_xy_ned=(0.0, 0.0), z_ned=z)
        self._set_mode(SimMode.OFFBOARD, what="OFFBOARD")

    def vertical_setpoint(self, z_ned: float) -> float:
        """z position: the vehicle holds altitude itself."""
        return z_ned

    def set_mode(self, mode: SimMode) -> None:
        """Any :class:`SimMode` by MAV_CMD_DO_SET_MODE, confirmed."""
        self._set_mode(SimMode(mode), what=SimMode(mode).name)

    def land(self) -> None:
        """MAV_CMD_NAV_LAND, confirmed by LAND (or DISARMED when already down)."""
        self.link.command_long(mavlink.MAV_CMD_NAV_LAND)
        self._wait_heartbeat(lambda hb: hb.custom_mode in (SimMode.LAND, SimMode.DISARMED),
                             "mode LAND")
