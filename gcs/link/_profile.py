"""Autopilot profiles: how each kind of vehicle is armed, launched, switched and landed.

The GCS loop is the same for every vehicle; what differs between the
simulated vehicles, PX4 and ArduPilot is the order of commands and the
setpoint channels. A profile is bound to one :class:`~gcs.link.Link`.
Every step waits for ``COMMAND_ACK`` (with the link's retries) and then for
the HEARTBEAT to confirm the new state, so a call that returns has happened.
All methods block; run them off the 4 Hz loop's thread.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from enum import Enum
from types import MappingProxyType
from typing import Protocol

from gcs.link._errors import CommandResult, LinkError
from gcs.link._link import DEFAULT_TELEMETRY_RATES_HZ, Link
from gcs.link._params import ParamClient
from gcs.wire import (
    CUSTOM_MODE_ENABLED,
    Heartbeat,
    LocalPosition,
    SetpointKind,
    Telemetry,
    mavlink,
    message_id,
)

__all__ = [
    "REAL_AUTOPILOT_RATES_HZ",
    "TEAM_FRAME_RATES_HZ",
    "AutopilotProfile",
    "ProfileBase",
    "ProfileName",
]

TEAM_FRAME_RATES_HZ: Mapping[str, float] = MappingProxyType({
    "GLOBAL_POSITION_INT": 5.0,
    "GPS_GLOBAL_ORIGIN": 0.5,
    "HOME_POSITION": 0.5,
})
"""What ties a real autopilot's local frame to the team frame, Hz (``gcs.loop`` places every
vehicle through it): its local origin, its global position (with LOCAL_POSITION_NED, the
origin again when the autopilot does not report it) and its home; asked for so the
``.tlog`` holds them too."""

REAL_AUTOPILOT_RATES_HZ: Mapping[str, float] = MappingProxyType(
    {**DEFAULT_TELEMETRY_RATES_HZ, **TEAM_FRAME_RATES_HZ})
"""What the PX4 and ArduPilot profiles ask for when first heard."""

PREPARE_TIMEOUT_S = 0.5
"""Wait for each telemetry request's ack, s, one attempt: a vehicle that does not answer must
not hold the link's command lock (arm, take-off, an abort's land) for long."""


class ProfileName(Enum):
    """Autopilot kinds a link can be configured with."""

    SIM = "sim"
    PX4 = "px4"
    ARDUPILOT = "ardupilot"

    @property
    def text(self) -> str:
        """Readable name."""
        return {"sim": "simulated vehicle", "px4": "PX4", "ardupilot": "ArduPilot"}[self.value]


class AutopilotProfile(Protocol):
    """What the GCS can ask of any vehicle, whatever its autopilot."""

    @property
    def name(self) -> ProfileName:
        """Which autopilot this profile drives."""
        ...

    @property
    def link(self) -> Link:
        """The vehicle's link."""
        ...

    @property
    def setpoint_kind(self) -> SetpointKind:
        """Channels of the setpoints this profile sends."""
        ...

    @property
    def streaming_mode(self) -> str:
        """:meth:`mode_text` of the mode that flies the GCS's setpoints (e.g. ``OFFBOARD``)."""
        ...

    @property
    def landing_modes(self) -> frozenset[str]:
        """:meth:`mode_text` of the modes in which the vehicle comes down on its own."""
        ...

    def mode_text(self, heartbeat: Heartbeat | None = None) -> str:
        """Flight mode of ``heartbeat`` (default: the latest), readable; ``"unknown"`` if none."""
        ...

    def arm(self) -> None:
        """Arm the motors and wait until the HEARTBEAT says armed."""
        ...

    def disarm(self) -> None:
        """Disarm and wait until the HEARTBEAT says disarmed."""
        ...

    def takeoff(self, *, altitude_m: float) -> None:
        """Arm and climb ``altitude_m`` above the current position; returns once the climb began."""
        ...

    def start_offboard(self, *, z_ned: float | None = None) -> None:
        """Hand control to GCS setpoints, holding ``z_ned`` (default: current z) meanwhile.

        From then on the caller must keep sending setpoints at more than 2 Hz.
        """
        ...

    def keep_climbing(self) -> None:
        """Called while the caller waits for a take-off to reach its altitude, before its
        own setpoints: whatever the profile streams for the take-off goes on."""
        ...

    @property
    def vertical_is_z(self) -> bool:
        """Whether :meth:`vertical_setpoint` is ``z_ned`` itself and does nothing else: the
        loop then fills it in for the whole fleet, without a call per vehicle."""
        ...

    def vertical_setpoint(self, z_ned: float) -> float:
        """The vertical channel (:attr:`setpoint_kind`) of the next setpoint for target ``z_ned``.

        z itself (m, down) for x/y acceleration with z position; the down
        acceleration (m/s^2) of the profile's own altitude loop for acceleration
        only. Called once per setpoint sent (unless :attr:`vertical_is_z`): the
        loop packs a whole fleet's setpoints at once and sends them with
        :class:`~gcs.link.Fanout`.
        """
        ...

    def send_setpoint(self, *, accel_xy_ned: tuple[float, float], z_ned: float) -> None:
        """Send horizontal acceleration (m/s^2) and the z to hold (down, m); non-blocking."""
        ...

    def land(self) -> None:
        """Land where the vehicle is."""
        ...

    def prepare(self) -> dict[str, CommandResult]:
        """Once, when the vehicle is first heard: ask for the telemetry the GCS needs.

        Returns each request's result (empty when nothing is asked); a
        refusal is the caller's to report, never an error.
        """
        ...

    @property
    def tilt_limit_param(self) -> str | None:
        """The autopilot's parameter that bounds its tilt (None: the GCS cannot read one)."""
        ...

    def tilt_limit_deg(self) -> float:
        """The autopilot's tilt limit, degrees (read from :attr:`tilt_limit_param`)."""
        ...

    def known_tilt_limit_deg(self) -> float | None:
        """The tilt limit as last heard, degrees, without asking (None: not heard yet)."""
        ...

    def set_tilt_limit_deg(self, degrees: float) -> float:
        """Set the tilt limit; the value read back afterwards, degrees."""
        ...

    def request_message(self, message: str) -> None:
        """Ask for one ``message`` now (MAV_CMD_REQUEST_MESSAGE); CommandError if refused."""
        ...


class ProfileBase:
    """Steps shared by all profiles: arming, confirmed mode changes, autopilot check."""

    expected_autopilots: frozenset[int] = frozenset()
    """``MAV_AUTOPILOT`` values this profile can drive."""

    vertical_is_z: bool = False
    """See :attr:`AutopilotProfile.vertical_is_z`."""

    telemetry_rates_hz: Mapping[str, float] = MappingProxyType({})
    """What :meth:`prepare` asks for (SET_MESSAGE_INTERVAL); empty: the vehicle's own rates."""

    tilt_limit_param: str | None = None
    """See :attr:`AutopilotProfile.tilt_limit_param`."""

    tilt_units_per_deg: float = 1.0
    """Units of :attr:`tilt_limit_param` per degree (ArduPilot's centidegrees: 100)."""

    params_bytewise: bool = False
    """Whether integer parameters travel byte for byte in the float field (PX4)."""

    def __init__(self, link: Link, *, confirm_timeout_s: float = 3.0) -> None:
        self._link = link
        self._confirm_timeout_s = confirm_timeout_s
        self._mode_names: dict[int, str] = {}
        self.params = ParamClient(link, bytewise=self.params_bytewise)
        """The vehicle's parameters (read, set and read back)."""

    @property
    def link(self) -> Link:
        """The vehicle's link."""
        return self._link

    def keep_climbing(self) -> None:
        """Nothing: the autopilot climbs on its own command (NAV_TAKEOFF, a simulated
        vehicle's climb)."""

    def send_setpoint(self, *, accel_xy_ned: tuple[float, float], z_ned: float) -> None:
        """Horizontal acceleration plus the profile's vertical channel for ``z_ned``."""
        vertical = self.vertical_setpoint(z_ned)  # type: ignore[attr-defined]
        if self.setpoint_kind is SetpointKind.ACCEL:  # type: ignore[attr-defined]
            self._link.send_setpoint(accel_xy_ned=accel_xy_ned, az_ned=vertical)
        else:
            self._link.send_setpoint(accel_xy_ned=accel_xy_ned, z_ned=vertical)

    def prepare(self) -> dict[str, CommandResult]:
        """Ask for :attr:`telemetry_rates_hz`, one quick attempt each; each message's result
        (see the protocol)."""
        if not self.telemetry_rates_hz:
            return {}
        return self._link.request_telemetry(self.telemetry_rates_hz,
                                            timeout_s=PREPARE_TIMEOUT_S, retries=0)

    def _tilt_param(self) -> str:
        if self.tilt_limit_param is None:
            raise LinkError(self._link.sysid, "its autopilot has no tilt limit the GCS can read")
        return self.tilt_limit_param

    def tilt_limit_deg(self) -> float:
        """The autopilot's tilt limit, degrees; LinkError when it does not answer."""
        return self.params.read(self._tilt_param()).value / self.tilt_units_per_deg

    def known_tilt_limit_deg(self) -> float | None:
        """The tilt limit as last heard (read, set, or announced by the autopilot), degrees;
        None when not heard yet or there is none. Sends nothing."""
        if self.tilt_limit_param is None:
            return None
        value = self.params.latest(self.tilt_limit_param)
        return None if value is None else value.value / self.tilt_units_per_deg

    def set_tilt_limit_deg(self, degrees: float) -> float:
        """Set the tilt limit (PARAM_SET), read it back; the value read back, degrees."""
        name = self._tilt_param()
        return self.params.set(name, degrees * self.tilt_units_per_deg).value \
            / self.tilt_units_per_deg

    def request_message(self, message: str) -> None:
        """MAV_CMD_REQUEST_MESSAGE for ``message`` (a name), one quick attempt."""
        self._link.command_long(mavlink.MAV_CMD_REQUEST_MESSAGE, (float(message_id(message)),),
                                timeout_s=PREPARE_TIMEOUT_S, retries=0)

    def mode_text(self, heartbeat: Heartbeat | None = None) -> str:
        """Flight mode of ``heartbeat`` (default: the latest), readable; ``"unknown"`` if none.

        Callers that already hold a telemetry snapshot pass its heartbeat, so the
        4 Hz loop does not take a second snapshot per vehicle.
        """
        hb = heartbeat if heartbeat is not None else self._link.telemetry.heartbeat
        if hb is None:
            return "unknown"
        name = self._mode_names.get(hb.custom_mode)
        if name is None:  # a handful of modes: remember their names (read per vehicle per tick)
            name = self._mode_names[hb.custom_mode] = self._mode_name(hb.custom_mode)
        return name

    def _mode_name(self, custom_mode: int) -> str:
        """The autopilot's name for ``custom_mode``."""
        raise NotImplementedError

    def arm(self) -> None:
        """MAV_CMD_COMPONENT_ARM_DISARM(1), confirmed by the HEARTBEAT."""
        self._check_autopilot()
        self._link.command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (1.0,))
        self._wait_heartbeat(lambda hb: hb.armed, "the vehicle to report armed")

    def disarm(self) -> None:
        """MAV_CMD_COMPONENT_ARM_DISARM(0), confirmed by the HEARTBEAT."""
        self._link.command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0.0,))
        self._wait_heartbeat(lambda hb: not hb.armed, "the vehicle to report disarmed")

    def _set_mode(self, main: int, sub: int = 0, *, what: str) -> None:
        """MAV_CMD_DO_SET_MODE with custom mode (main, sub), confirmed by the HEARTBEAT."""
        self._link.command_long(mavlink.MAV_CMD_DO_SET_MODE,
                                (float(CUSTOM_MODE_ENABLED), float(main), float(sub)))
        self._wait_heartbeat(lambda hb: self._mode_is(hb, main, sub), f"mode {what}")

    def _mode_is(self, heartbeat: Heartbeat, main: int, sub: int) -> bool:
        """Whether the HEARTBEAT shows mode (main, sub); PX4 packs them differently."""
        return heartbeat.custom_mode == main

    def _wait_heartbeat(self, ok: Callable[[Heartbeat], bool], what: str) -> Heartbeat:
        def predicate(t: Telemetry) -> bool:
            return t.heartbeat is not None and ok(t.heartbeat)

        hb = self._link.wait_for(predicate, timeout_s=self._confirm_timeout_s, what=what).heartbeat
        assert hb is not None
        return hb

    def _check_autopilot(self) -> None:
        hb = self._wait_heartbeat(lambda hb: True, "a HEARTBEAT")
        if self.expected_autopilots and hb.autopilot not in self.expected_autopilots:
            entry = mavlink.enums["MAV_AUTOPILOT"].get(hb.autopilot)
            name = entry.name if entry is not None else str(hb.autopilot)
            raise LinkError(self._link.sysid, f"reports autopilot {name}, which the "
                                              f"'{type(self).__name__}' profile cannot drive")

    def _position(self, *, max_age_s: float = 1.0) -> LocalPosition:
        position = self._link.telemetry.position
        if position is None:
            raise LinkError(self._link.sysid, "no LOCAL_POSITION_NED received yet")
        age = self._link.clock() - position.received_at
        if age > max_age_s:
            raise LinkError(self._link.sysid, f"LOCAL_POSITION_NED is {age:.1f} s old")
        return position
