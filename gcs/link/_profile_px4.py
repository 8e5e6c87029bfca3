"""Profile of PX4 in OFFBOARD mode.

PX4 accepts OFFBOARD only after setpoints have streamed for a while (above
2 Hz, about a second) and leaves it when they stop for ``COM_OF_LOSS_T``.
So every way into OFFBOARD first streams "hold" setpoints from a helper
thread for :attr:`Px4Profile.warmup_s`, then sends MAV_CMD_DO_SET_MODE with
custom main mode OFFBOARD (6). The helper keeps streaming until the caller's
first own setpoint (hand-over), or at most ``handover_s``: if the GCS loop
never takes over, the stream stops and PX4's offboard-loss failsafe acts.

Take-off: warm-up stream of (z = current z - altitude, a_xy holding the
vehicle where the stream began), OFFBOARD, arm: PX4 climbs to the streamed z.
Setpoints are x/y acceleration + z position. Land: MAV_CMD_NAV_LAND
(AUTO.LAND). Tilt limit: ``MPC_TILTMAX_AIR`` (degrees); integer parameters
travel byte for byte.
"""

from __future__ import annotations

import math
import threading
import time

from gcs.common import HOLD_KP, HOLD_KV, join_thread
from gcs.link._errors import LinkError
from gcs.link._link import Link
from gcs.link._profile import REAL_AUTOPILOT_RATES_HZ, ProfileBase, ProfileName
from gcs.wire import (
    Heartbeat,
    Px4AutoSubMode,
    Px4MainMode,
    SetpointKind,
    mavlink,
    px4_mode_text,
    split_px4_custom_mode,
)

__all__ = ["Px4Profile"]


HOLD_ACCEL_MAX = 1.0
"""Largest horizontal acceleration the hold stream asks for, m/s^2."""

HOLD_FRESH_S = 0.5
"""Oldest LOCAL_POSITION_NED the hold stream steers by, s; older: zero acceleration."""


def hold_accel(p_xy: tuple[float, float], v_xy: tuple[float, float],
               hold_xy: tuple[float, float]) -> tuple[float, float]:
    """The horizontal acceleration that holds a vehicle at ``hold_xy`` (NED, m) from its
    position and velocity, at most :data:`HOLD_ACCEL_MAX`. Zero acceleration (the stream's
    first) is no hold: it keeps whatever velocity the vehicle has, and four PX4 SIH quads
    drift up to 2.8 m apart in a 15 s climb."""
    ax = -HOLD_KV * v_xy[0] - HOLD_KP * (p_xy[0] - hold_xy[0])
    ay = -HOLD_KV * v_xy[1] - HOLD_KP * (p_xy[1] - hold_xy[1])
    norm = math.hypot(ax, ay)
    if not math.isfinite(norm):
        return 0.0, 0.0
    if norm > HOLD_ACCEL_MAX:
        ax, ay = ax * HOLD_ACCEL_MAX / norm, ay * HOLD_ACCEL_MAX / norm
    return ax, ay


class _HoldStream:
    """Streams a hold setpoint from a thread until stopped or past its deadline: ``z_ned``,
    and the horizontal position where it began, held by acceleration
    (:func:`hold_accel`)."""

    def __init__(self, link: Link, *, z_ned: float, rate_hz: float) -> None:
        self._link = link
        self._z_ned = z_ned
        position = link.telemetry.position
        self._hold_xy = None if position is None else (position.p_ned[0], position.p_ned[1])
        self._period = 1.0 / rate_hz
        self._deadline = float("inf")
        self._stop = threading.Event()
        self.started_at = time.monotonic()
        self._thread = threading.Thread(target=self._run, daemon=True,
                                        name=f"px4-hold-{link.sysid}")
        self._thread.start()

    def end_within(self, seconds: float) -> None:
        """Stop streaming at the latest ``seconds`` from now."""
        self._deadline = time.monotonic() + seconds

    def _run(self) -> None:
        while not self._stop.is_set() and time.monotonic() < self._deadline:
            try:
                self._link.send_setpoint(accel_xy_ned=self._accel(), z_ned=self._z_ned)
            except LinkError:
                return  # link closed
            self._stop.wait(self._period)

    def _accel(self) -> tuple[float, float]:
        position = self._link.telemetry.position
        if position is None or self._link.clock() - position.received_at > HOLD_FRESH_S:
            return 0.0, 0.0
        p, v = position.p_ned, position.v_ned
        if self._hold_xy is None:
            self._hold_xy = (p[0], p[1])
        return hold_accel((p[0], p[1]), (v[0], v[1]), self._hold_xy)

    def stop(self) -> None:
        self._stop.set()
        join_thread(self._thread, 1.0, what="a PX4 setpoint warm-up")


class Px4Profile(ProfileBase):
    """Drives PX4 through OFFBOARD; see the module docstring."""

    expected_autopilots = frozenset({mavlink.MAV_AUTOPILOT_PX4})
    streaming_mode = Px4MainMode.OFFBOARD.name
    landing_modes = frozenset(f"AUTO.{m.name}" for m in (Px4AutoSubMode.LAND,
                                                        Px4AutoSubMode.RTL,
                                                        Px4AutoSubMode.PRECLAND))
    telemetry_rates_hz = REAL_AUTOPILOT_RATES_HZ
    tilt_limit_param = "MPC_TILTMAX_AIR"  # degrees
    params_bytewise = True

    def __init__(self, link: Link, *, confirm_timeout_s: float = 3.0, warmup_s: float = 1.2,
                 stream_rate_hz: float = 10.0, handover_s: float = 5.0) -> None:
        super().__init__(link, confirm_timeout_s=confirm_timeout_s)
        if warmup_s < 1.0 or stream_rate_hz <= 2.0:
            raise ValueError("PX4 needs setpoints above 2 Hz for at least 1 s before OFFBOARD")
        self.warmup_s = warmup_s
        """Setpoint streaming before the OFFBOARD command, s."""
        self.stream_rate_hz = stream_rate_hz
        """Rate of the warm-up and bridge stream, Hz."""
        self.handover_s = handover_s
        """Longest bridge from a returned take-off to the caller's first own setpoint, s."""
        self._stream: _HoldStream | None = None
        self._stream_lock = threading.Lock()

    @property
    def name(self) -> ProfileName:
        """Always :attr:`ProfileName.PX4`."""
        return ProfileName.PX4

    @property
    def setpoint_kind(self) -> SetpointKind:
        """x/y acceleration with z position."""
        return SetpointKind.ACCEL_XY_POS_Z

    def _mode_name(self, custom_mode: int) -> str:
        """PX4 mode such as ``OFFBOARD`` or ``AUTO.LAND``."""
        return px4_mode_text(custom_mode)

    def takeoff(self, *, altitude_m: float) -> None:
        """Stream a hold ``altitude_m`` above, switch to OFFBOARD, then arm."""
        if not altitude_m > 0:
            raise ValueError(f"altitude_m must be positive, got {altitude_m}")
        self._check_autopilot()
        z_ned = self._position().p_ned[2] - altitude_m
        try:
            self._enter_offboard(z_ned)
            self.arm()
        except Exception:
            self._stop_stream()
            raise
        self._hand_over()

    def start_offboard(self, *, z_ned: float | None = None) -> None:
        """Warm-up stream then OFFBOARD (nothing to do if already in OFFBOARD)."""
        hb = self.link.telemetry.heartbeat
        if hb is not None and self._mode_is(hb, Px4MainMode.OFFBOARD, 0):
            return
        z = self._position().p_ned[2] if z_ned is None else z_ned
        try:
            self._enter_offboard(z)
        except Exception:
            self._stop_stream()
            raise
        self._hand_over()

    def keep_climbing(self) -> None:
        """The take-off's stream goes on for another ``handover_s``: a climb slower than
        that (four PX4 SIH quads take 6 s to 0.9 m) would lose its stream and go to RTL
        on PX4's offboard-loss failsafe before the GCS loop takes over."""
        self._hand_over()

    def vertical_setpoint(self, z_ned: float) -> float:
        """z position; the loop's setpoints take over from the warm-up stream."""
        self._stop_stream()
        return z_ned

    def set_mode(self, main: Px4MainMode, sub: Px4AutoSubMode | None = None) -> None:
        """Any PX4 mode by MAV_CMD_DO_SET_MODE, confirmed (OFFBOARD: use :meth:`start_offboard`)."""
        sub_value = 0 if sub is None else int(sub)
        self._set_mode(int(main), sub_value, what=f"{Px4MainMode(main).name}"
                       + (f".{Px4AutoSubMode(sub).name}" if sub is not None else ""))

    def land(self) -> None:
        """MAV_CMD_NAV_LAND, confirmed by AUTO.LAND."""
        self._stop_stream()
        self.link.command_long(mavlink.MAV_CMD_NAV_LAND)
        self._wait_heartbeat(
            lambda hb: self._mode_is(hb, Px4MainMode.AUTO, Px4AutoSubMode.LAND), "mode AUTO.LAND")

    def _enter_offboard(self, z_ned: float) -> None:
        """Start the hold stream, let it run ``warmup_s``, then switch to OFFBOARD."""
        self._stop_stream()
        stream = _HoldStream(self.link, z_ned=z_ned, rate_hz=self.stream_rate_hz)
        with self._stream_lock:
            self._stream = stream
        time.sleep(max(0.0, stream.started_at + self.warmup_s - time.monotonic()))
        self._set_mode(Px4MainMode.OFFBOARD, 0, what="OFFBOARD")

    def _hand_over(self) -> None:
        """Keep the hold stream only as a bridge to the caller's own setpoints."""
        with self._stream_lock:
            if self._stream is not None:
                self._stream.end_within(self.handover_s)

    def _stop_stream(self) -> None:
        with self._stream_lock:
            stream, self._stream = self._stream, None
        if stream is not None:
            stream.stop()

    def _mode_is(self, heartbeat: Heartbeat, main: int, sub: int) -> bool:
        got_main, got_sub = split_px4_custom_mode(heartbeat.custom_mode)
        return got_main == main and (sub == 0 or got_sub == sub)
