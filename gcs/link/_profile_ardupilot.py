"""Profile of ArduCopter in GUIDED mode, with the GCS-side vertical loop.

ArduCopter takes position, velocity and acceleration targets only as whole
three-axis groups; with acceleration only there is no altitude hold, so the
GCS closes the vertical loop from LOCAL_POSITION_NED with
:class:`VerticalPd` and sends ``afz`` (:data:`~gcs.wire._setpoints.MASK_ACCEL`).
The loop runs at telemetry rate: every LOCAL_POSITION_NED that arrives while
the GCS streams setpoints gets a setpoint of its own, with the horizontal
acceleration last sent and ``afz`` from that very position, so the altitude
loop does not wait for the 4 Hz guidance (or its re-sends) to see a climb.
``GUID_TIMEOUT`` (3 s) zeroes the targets if setpoints stop. On first contact
the profile asks for LOCAL_POSITION_NED and ATTITUDE at 20 Hz
(:meth:`~gcs.link._profile.ProfileBase.prepare`), far above ArduPilot's
default stream rates on most ports.

Arm: MAV_CMD_DO_SET_MODE GUIDED (4) first, then arm: ArduCopter armed in
another mode (STABILIZE) and switched to GUIDED later flies its first seconds on
its pilot's sticks. Take-off: GUIDED and armed (either done only if needed),
then MAV_CMD_NAV_TAKEOFF (param7 = altitude above home, m) at once: an armed
copter left on the ground disarms itself (``DISARM_DELAY``). Land:
MAV_CMD_DO_SET_MODE LAND (9). Tilt limit: ``ANGLE_MAX``, centidegrees.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

from gcs.common import field
from gcs.link._errors import LinkError
from gcs.link._link import Link
from gcs.link._profile import REAL_AUTOPILOT_RATES_HZ, ProfileBase, ProfileName
from gcs.transport import FrameDirection
from gcs.wire import (
    SETPOINT_MESSAGE,
    CopterMode,
    Heartbeat,
    LocalPosition,
    SetpointKind,
    TelemetryRecord,
    copter_mode_text,
    mavlink,
    unpack_v2,
)

__all__ = ["ArduPilotProfile", "VerticalPd"]


@dataclass(frozen=True)
class VerticalPd:
    """PD law on altitude giving the down acceleration ArduCopter needs (gravity excluded).

    ``az = kp (z_ref - z) + kd (vz_ref - vz)``, clipped to ``±az_max``. The
    defaults give a natural frequency of 1 rad/s and damping 0.7: slow enough
    for a 4 Hz loop, and the payload's weight is a disturbance the vehicle's
    own controller rejects.
    """

    kp: float = field(doc="position gain, 1/s^2", default=1.0, gt=0.0)
    kd: float = field(doc="velocity gain, 1/s", default=1.4, ge=0.0)
    az_max: float = field(doc="largest commanded vertical acceleration, m/s^2",
                          default=2.0, gt=0.0)

    def accel_down(self, *, z_ref_ned: float, z_ned: float, vz_ned: float,
                   vz_ref_ned: float = 0.0) -> float:
        """Down acceleration, m/s^2, from reference and measured z (m) and vz (m/s), NED."""
        az = self.kp * (z_ref_ned - z_ned) + self.kd * (vz_ref_ned - vz_ned)
        if not math.isfinite(az):
            raise ValueError(f"vertical loop input not finite: z_ref={z_ref_ned} z={z_ned} "
                             f"vz={vz_ned}")
        return max(-self.az_max, min(self.az_max, az))


class ArduPilotProfile(ProfileBase):
    """Drives ArduCopter through GUIDED; see the module docstring."""

    expected_autopilots = frozenset({mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA})
    streaming_mode = CopterMode.GUIDED.name
    landing_modes = frozenset(m.name for m in (CopterMode.LAND, CopterMode.RTL,
                                               CopterMode.SMART_RTL))
    telemetry_rates_hz = REAL_AUTOPILOT_RATES_HZ
    tilt_limit_param = "ANGLE_MAX"
    tilt_units_per_deg = 100.0  # centidegrees

    def __init__(self, link: Link, *, confirm_timeout_s: float = 3.0,
                 vertical: VerticalPd | None = None, max_position_age_s: float = 0.5,
                 follow_s: float = 0.5) -> None:
        super().__init__(link, confirm_timeout_s=confirm_timeout_s)
        self.vertical = vertical if vertical is not None else VerticalPd()
        """The vertical loop closed on the GCS."""
        self.max_position_age_s = max_position_age_s
        """Oldest LOCAL_POSITION_NED the vertical loop may use, s."""
        self.follow_s = follow_s
        """Positions get setpoints of their own while the caller's last one is this recent, s
        (the GCS loop re-sends at 12 Hz: older means it stopped streaming)."""
        self._lock = threading.Lock()
        self._z_ref: float | None = None  # the altitude target of the last setpoint sent, m
        self._z_ref_at = -math.inf  # link clock time it was sent
        self._z_next: float | None = None  # the caller's target, until its setpoint is sent
        self._own = threading.local()  # .sending: this thread sends a per-position setpoint
        self._accel_xy = (0.0, 0.0)  # horizontal acceleration last sent, m/s^2
        self._guided = False  # whether the latest HEARTBEAT shows GUIDED
        link.add_frame_listener(self._on_frame)
        link.add_record_listener(self._on_record)

    @property
    def name(self) -> ProfileName:
        """Always :attr:`ProfileName.ARDUPILOT`."""
        return ProfileName.ARDUPILOT

    @property
    def setpoint_kind(self) -> SetpointKind:
        """Acceleration on all three axes."""
        return SetpointKind.ACCEL

    def _mode_name(self, custom_mode: int) -> str:
        """ArduCopter mode name such as ``GUIDED``."""
        return copter_mode_text(custom_mode)

    def arm(self) -> None:
        """GUIDED (unless in it already), then arm, each confirmed by the HEARTBEAT."""
        self._check_autopilot()
        self._ensure_guided()
        super().arm()

    def takeoff(self, *, altitude_m: float) -> None:
        """GUIDED and armed (each only if needed), then NAV_TAKEOFF to ``altitude_m`` above
        home right away."""
        if not altitude_m > 0:
            raise ValueError(f"altitude_m must be positive, got {altitude_m}")
        self._check_autopilot()
        self._ensure_guided()
        hb = self.link.telemetry.heartbeat
        if hb is None or not hb.armed:
            super().arm()
        self.link.command_long(mavlink.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, 0, 0, 0, altitude_m))

    def _ensure_guided(self) -> None:
        hb = self.link.telemetry.heartbeat
        if hb is None or hb.custom_mode != CopterMode.GUIDED:
            self.set_mode(CopterMode.GUIDED)

    def start_offboard(self, *, z_ned: float | None = None) -> None:
        """Make sure the vehicle is in GUIDED (ArduCopter has no separate offboard mode)."""
        self._ensure_guided()
        if z_ned is not None:
            self.send_setpoint(accel_xy_ned=(0.0, 0.0), z_ned=z_ned)

    def vertical_setpoint(self, z_ned: float) -> float:
        """``afz`` from :attr:`vertical` and the latest position (acceleration on three axes).

        Called for every setpoint the GCS sends; ``z_ned`` becomes the target
        the positions arriving until the next call are steered to.
        """
        position = self._position(max_age_s=self.max_position_age_s)
        az = self.vertical.accel_down(z_ref_ned=z_ned, z_ned=position.p_ned[2],
                                      vz_ned=position.v_ned[2])
        with self._lock:  # followed once its setpoint goes out, with that setpoint's afx, afy
            self._z_next = z_ned
        return az

    def _on_frame(self, direction: FrameDirection, frame: bytes) -> None:
        """Remember the horizontal acceleration of every setpoint sent, and the altitude
        target it was computed for (under the send lock: quick, and never sends). Taken
        together, so a position arriving between the caller's target and its setpoint is
        never answered with the new target and the old acceleration (under load the
        first per-position setpoint would carry (0, 0))."""
        if direction is not FrameDirection.OUT or len(frame) < 12 or frame[0] != 0xFD:
            return
        if int.from_bytes(frame[7:10], "little") != SETPOINT_MESSAGE.id:
            return
        msg = unpack_v2(bytearray(frame), msgid=SETPOINT_MESSAGE.id,
                        signature_len=13 if frame[2] & 1 else 0)
        if msg is not None:
            now = self.link.clock()
            with self._lock:
                self._accel_xy = (float(msg.afx), float(msg.afy))
                if self._z_next is not None and not getattr(self._own, "sending", False):
                    self._z_ref, self._z_ref_at, self._z_next = self._z_next, now, None

    def _on_record(self, record: TelemetryRecord) -> None:
        """A new position while the GCS streams: a setpoint with ``afz`` from it (receive
        thread)."""
        if isinstance(record, Heartbeat):
            self._guided = record.custom_mode == CopterMode.GUIDED
            return
        if not isinstance(record, LocalPosition):
            return
        with self._lock:
            z_ref, accel_xy = self._z_ref, self._accel_xy
            fresh = record.received_at - self._z_ref_at <= self.follow_s
        # GUIDED flies setpoints; in LAND or RTL they would be refused
        if z_ref is None or not fresh or not self._guided:
            return
        try:
            az = self.vertical.accel_down(z_ref_ned=z_ref, z_ned=record.p_ned[2],
                                          vz_ned=record.v_ned[2])
            self._own.sending = True  # its frame is not the caller's (:meth:`_on_frame`)
            self.link.send_setpoint(accel_xy_ned=accel_xy, az_ned=az)
        except (ValueError, LinkError):
            return  # a bad position or a closed link: the GCS loop reports its own sends
        finally:
            self._own.sending = False

    def set_mode(self, mode: CopterMode) -> None:
        """Any ArduCopter mode by MAV_CMD_DO_SET_MODE, confirmed; leaving GUIDED ends the
        setpoints sent per position until the caller streams again."""
        if mode != CopterMode.GUIDED:
            with self._lock:
                self._z_ref = self._z_next = None
        self._set_mode(int(mode), what=CopterMode(mode).name)

    def land(self) -> None:
        """Mode LAND."""
        self.set_mode(CopterMode.LAND)
