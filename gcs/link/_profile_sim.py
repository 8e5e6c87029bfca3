"""Profile of the simulated vehicles (this repository's onboard autopilot).

The vehicles present themselves as PX4 (``MAV_AUTOPILOT_PX4``, PX4's custom
main and sub modes: :data:`gcs.wire.SIM_PX4_MODES`); the profile names their
modes by the autopilot's own :class:`SimMode` (AUTO.LOITER, POSCTL and ALTCTL
are HOLD; a vehicle that is not armed is DISARMED). Simulators before PX4's
identity (``MAV_AUTOPILOT_GENERIC``, ``custom_mode`` = the :class:`SimMode`
value) are driven with their own numbers.

Sequence, every step acknowledged and confirmed by the HEARTBEAT:

- take-off: arm (MAV_CMD_COMPONENT_ARM_DISARM), then MAV_CMD_NAV_TAKEOFF with
  param7 = climb above the current position, m; the vehicle reports
  TAKEOFF (AUTO.TAKEOFF) and then HOLD (AUTO.LOITER);
- offboard: one hold setpoint, then MAV_CMD_DO_SET_MODE to OFFBOARD (PX4 main
  mode 6); setpoints are x/y acceleration + z position;
- land: MAV_CMD_NAV_LAND (LAND, AUTO.LAND); disarm once on the ground.
"""

from __future__ import annotations

from gcs.link._profile import ProfileBase, ProfileName
from gcs.wire import (
    SIM_PX4_MODES,
    Heartbeat,
    SetpointKind,
    SimMode,
    mavlink,
    px4_mode_text,
    sim_mode_for_px4,
    sim_mode_of,
    sim_mode_text,
    split_px4_custom_mode,
)

__all__ = ["SimProfile"]


class SimProfile(ProfileBase):
    """Drives a simulated vehicle; see the module docstring for the sequence."""

    expected_autopilots = frozenset({mavlink.MAV_AUTOPILOT_PX4, mavlink.MAV_AUTOPILOT_GENERIC})
    streaming_mode = SimMode.OFFBOARD.name
    landing_modes = frozenset({SimMode.LAND.name})
    vertical_is_z = True
    params_bytewise = True  # as PX4: integer parameters travel byte for byte
    tilt_limit_param = "MPC_TILTMAX_AIR"
    """The simulator's ``bank_max_deg`` under PX4's name (:mod:`vehicles._params`), degrees.

    Unlike PX4's, it bounds roll and pitch each, not the tilt: a command along a
    diagonal tilts the vehicle up to ``acos(cos(b)^2)`` (28.0 degrees at 20). The
    config's ``limits.bank_deg`` is the same kind of bound ("largest roll/pitch
    angle": the paper's and Paparazzi's), so the two compare as they are, and
    ``limits.autopilot_tilt: set`` writes the bank limit itself. (A tilt bound, PX4's or
    ArduPilot's, bounds roll and pitch too, as neither exceeds the tilt: there the same
    comparison is the stricter one.) Read as a tilt, the shipped 20 degrees would have
    to be 14.2 to keep a diagonal within 20, and the paper's flight would change.
    """
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

    def mode_text(self, heartbeat: Heartbeat | None = None) -> str:
        """:class:`SimMode` name of ``heartbeat`` (default: the latest); ``"unknown"`` if none."""
        hb = heartbeat if heartbeat is not None else self.link.telemetry.heartbeat
        if hb is not None and _shown(hb) is SimMode.DISARMED:
            return SimMode.DISARMED.name
        return super().mode_text(hb)

    def _mode_name(self, custom_mode: int) -> str:
        """:class:`SimMode` name of an armed vehicle's custom mode (PX4's or a bare SimMode)."""
        mode = sim_mode_of(custom_mode)
        if mode is not None:
            return mode.name
        return px4_mode_text(custom_mode) if custom_mode >= 0x10000 else sim_mode_text(custom_mode)

    def takeoff(self, *, altitude_m: float) -> None:
        """Arm, then NAV_TAKEOFF(param7 = ``altitude_m``); confirmed by TAKEOFF or HOLD."""
        if not altitude_m > 0:
            raise ValueError(f"altitude_m must be positive, got {altitude_m}")
        self.arm()
        self.link.command_long(mavlink.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, 0, 0, 0, altitude_m))
        self._wait_heartbeat(lambda hb: _shown(hb) in (SimMode.TAKEOFF, SimMode.HOLD),
                             "mode TAKEOFF")

    def start_offboard(self, *, z_ned: float | None = None) -> None:
        """Send a hold setpoint, then switch to OFFBOARD."""
        z = self._position().p_ned[2] if z_ned is None else z_ned
        self.link.send_setpoint(accel_xy_ned=(0.0, 0.0), z_ned=z)
        self.set_mode(SimMode.OFFBOARD)

    def vertical_setpoint(self, z_ned: float) -> float:
        """z position: the vehicle holds altitude itself."""
        return z_ned

    def set_mode(self, mode: SimMode) -> None:
        """Any :class:`SimMode` by MAV_CMD_DO_SET_MODE (DISARMED: by disarming), confirmed."""
        mode = SimMode(mode)
        if mode is SimMode.DISARMED:
            self.disarm()
            return
        hb = self.link.telemetry.heartbeat
        if hb is not None and hb.autopilot == mavlink.MAV_AUTOPILOT_GENERIC:
            main, sub = int(mode), 0
        else:
            main, sub = split_px4_custom_mode(SIM_PX4_MODES[mode])
        self._set_mode(main, sub, what=mode.name)

    def land(self) -> None:
        """MAV_CMD_NAV_LAND, confirmed by LAND (or DISARMED when already down)."""
        self.link.command_long(mavlink.MAV_CMD_NAV_LAND)
        self._wait_heartbeat(lambda hb: _shown(hb) in (SimMode.LAND, SimMode.DISARMED),
                             "mode LAND")

    def _mode_is(self, heartbeat: Heartbeat, main: int, sub: int) -> bool:
        """Whether the HEARTBEAT shows the mode DO_SET_MODE (main, sub) asked for."""
        wanted = (sim_mode_of(main) if heartbeat.autopilot == mavlink.MAV_AUTOPILOT_GENERIC
                  else sim_mode_for_px4(main, sub))
        return wanted is not None and _shown(heartbeat) is wanted


def _shown(heartbeat: Heartbeat) -> SimMode | None:
    """The :class:`SimMode` a simulated vehicle's HEARTBEAT shows (an earlier simulator's
    custom mode says DISARMED itself)."""
    legacy = heartbeat.autopilot == mavlink.MAV_AUTOPILOT_GENERIC
    return sim_mode_of(heartbeat.custom_mode, armed=heartbeat.armed or legacy)
