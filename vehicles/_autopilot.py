"""The onboard autopilots of a team: commands, setpoints, one control step, telemetry.

:class:`Autopilot` holds the state of N vehicles' autopilots in arrays and
advances them all with one numba call per 512 Hz step. Commands and setpoints
address one vehicle by index and take effect at the next step. Nothing here
blocks or talks to a network: a MAVLink endpoint maps SET_POSITION_TARGET_LOCAL_NED
onto the setpoint methods and COMMAND_LONG onto the command methods, whose
:class:`~vehicles.RequestOutcome` becomes the COMMAND_ACK.
"""

from __future__ import annotations

import math
import operator

import numpy as np

from gcs.wire import SetpointKind, SimMode
from vehicles._airframe import Airframe
from vehicles._config import AutopilotConfig
from vehicles._kernel import autopilot_step
from vehicles._outcomes import Denial, RequestOutcome
from vehicles._quaternion import euler_from_quaternions
from vehicles._state import (
    SHARED_SETTINGS,
    AutopilotParams,
    AutopilotState,
    Measurements,
    make_autopilot_params,
    make_autopilot_state,
    write_vehicle_params,
)
from vehicles._transitions import (
    enter_armed_hold,
    enter_disarmed,
    enter_hold,
    enter_land,
    enter_offboard,
    enter_takeoff,
)

__all__ = ["Autopilot"]

_ACCEPTED = RequestOutcome(True)


class Autopilot:
    """Onboard autopilots of ``n_vehicles`` identical rotorcraft.

    ``airframe`` is the autopilot's model of the vehicle (mass, thrust
    coefficient, geometry, rotor time constant); it may differ from the
    simulated truth, which is the point of INDI. ``config`` is every vehicle's
    configuration at the start; each vehicle's own can change later
    (:meth:`configure`, what PARAM_SET does).
    """

    def __init__(self, airframe: Airframe, config: AutopilotConfig, n_vehicles: int) -> None:
        if n_vehicles < 1:
            raise ValueError(f"need at least one vehicle, got {n_vehicles}")
        self.airframe = airframe
        self.config = config
        """The configuration every vehicle started with (see :meth:`vehicle_config`)."""
        self._configs = [config] * n_vehicles
        self.state: AutopilotState = make_autopilot_state(n_vehicles)
        self.params: AutopilotParams = make_autopilot_params(airframe, config, n_vehicles)
        _load_mode_entries()

    # -- stepping -----------------------------------------------------------------------------

    @property
    def n_vehicles(self) -> int:
        """Number of vehicles."""
        return int(self.state.mode.shape[0])

    @property
    def rate_hz(self) -> float:
        """Control loop rate, Hz."""
        return self.config.rate_hz

    @property
    def t(self) -> float:
        """Autopilot time, s (advances by 1 / rate_hz per step)."""
        return float(self.state.t[0])

    def step(self, measurements: Measurements) -> np.ndarray:
        """Run one control period on the latest measurements; returns rotor speed
        commands (N, 4) in rad/s. Simulations normally step through
        :meth:`sim.World.run`, which calls the same kernel in lockstep."""
        autopilot_step(self.state, self.params, measurements)
        return self.state.rotor_speed_cmd.copy()

    # -- configuration ------------------------------------------------------------------------

    def vehicle_config(self, i: int) -> AutopilotConfig:
        """Vehicle ``i``'s configuration now."""
        return self._configs[self._index(i)]

    def configure(self, i: int, config: AutopilotConfig) -> None:
        """Fly vehicle ``i`` with ``config`` from the next control period on.

        Every gain, limit and timeout may change in flight; the loop rate and the filter
        cutoffs (:data:`vehicles._state.SHARED_SETTINGS`) are the whole team's, and a
        ``config`` that changes them raises ValueError.
        """
        i = self._index(i)
        for name in SHARED_SETTINGS:
            if getattr(config, name) != getattr(self.config, name):
                raise ValueError(f"{name} is shared by every vehicle and cannot change")
        write_vehicle_params(self.params, i, self.airframe, config)
        self._configs[i] = config

    def origin_ned(self, i: int) -> np.ndarray:
        """Vehicle ``i``'s local origin in the sensor frame, m (copy)."""
        return self.state.origin_ned[self._index(i)].copy()

    def set_origin(self, i: int, origin_ned: np.ndarray | tuple[float, float, float]
                   ) -> RequestOutcome:
        """Re-base vehicle ``i``'s local frame on ``origin_ned`` (sensor frame, m), as an EKF
        takes a new origin; refused while armed (the hold points would jump)."""
        i = self._index(i)
        origin = _finite_vector(origin_ned, 3, "origin_ned")
        s = self.state
        if s.mode[i] != SimMode.DISARMED:
            return RequestOutcome(False, Denial.ARMED)
        s.p_est[i] -= origin - s.origin_ned[i]  # the estimate moves at once, not at next pose
        s.origin_ned[i] = origin
        return _ACCEPTED

    # -- commands (later COMMAND_LONG -> COMMAND_ACK) -------------------------------------------

    def arm(self, i: int) -> RequestOutcome:
        """Start the rotors at idle and HOLD on the ground; home altitude is set here."""
        i = self._index(i)
        if self.state.mode[i] != SimMode.DISARMED:
            return _ACCEPTED
        if self.state.pose_seq_seen[i] == 0:
            return RequestOutcome(False, Denial.NO_POSE)
        enter_armed_hold(self.state, i)
        return _ACCEPTED

    def disarm(self, i: int, *, force: bool = False) -> RequestOutcome:
        """Stop the rotors; refused in flight unless ``force`` (a kill switch)."""
        i = self._index(i)
        if not force and self._in_flight(i):
            return RequestOutcome(False, Denial.IN_FLIGHT)
        enter_disarmed(self.state, i)
        return _ACCEPTED

    def takeoff(self, i: int, altitude: float) -> RequestOutcome:
        """Climb to ``altitude`` m above the arming point, then HOLD there."""
        i = self._index(i)
        if self.state.mode[i] == SimMode.DISARMED:
            return RequestOutcome(False, Denial.DISARMED)
        if not altitude > self._configs[i].ground_clearance or not math.isfinite(altitude):
            return RequestOutcome(False, Denial.BAD_ALTITUDE)
        enter_takeoff(self.state, i, float(altitude))
        return _ACCEPTED

    def land(self, i: int) -> RequestOutcome:
        """Descend where the vehicle is and disarm on touchdown."""
        i = self._index(i)
        if self.state.mode[i] == SimMode.DISARMED:
            return RequestOutcome(False, Denial.DISARMED)
        enter_land(self.state, i)
        return _ACCEPTED

    def hold(self, i: int) -> RequestOutcome:
        """Hold the current position (lands after the hold timeout)."""
        i = self._index(i)
        if self.state.mode[i] == SimMode.DISARMED:
            return RequestOutcome(False, Denial.DISARMED)
        enter_hold(self.state, i)
        return _ACCEPTED

    def start_offboard(self, i: int) -> RequestOutcome:
        """Track external setpoints; needs a setpoint younger than the setpoint timeout."""
        i = self._index(i)
        if self.state.mode[i] == SimMode.DISARMED:
            return RequestOutcome(False, Denial.DISARMED)
        if self.t - self.state.sp_time[i] > self._configs[i].setpoint_timeout:
            return RequestOutcome(False, Denial.NO_SETPOINT_STREAM)
        enter_offboard(self.state, i)
        return _ACCEPTED

    # -- setpoints (later SET_POSITION_TARGET_LOCAL_NED) --------------------------------------

    def set_accel_setpoint(self, i: int, accel_ned: np.ndarray | tuple[float, float, float], *,
                           yaw: float | None = None) -> None:
        """Command a 3D acceleration (m/s^2, NED; gravity not included: zero means hover)
        and optionally a heading (rad). Used while in OFFBOARD; refreshes the stream."""
        i = self._index(i)
        a = _finite_vector(accel_ned, 3, "accel_ned")
        self._store_setpoint(i, SetpointKind.ACCEL, a, 0.0, yaw)

    def set_accel_xy_pos_z_setpoint(self, i: int, accel_xy_ned: np.ndarray | tuple[float, float],
                                    z_ned: float, *, yaw: float | None = None) -> None:
        """Command x/y acceleration (m/s^2, NED) and hold z at ``z_ned`` (m, NED) with
        eq. (pdalt); optionally a heading (rad). Used while in OFFBOARD; refreshes the
        stream."""
        i = self._index(i)
        a = _finite_vector(accel_xy_ned, 2, "accel_xy_ned")
        if not math.isfinite(z_ned):
            raise ValueError(f"z_ned must be finite, got {z_ned}")
        self._store_setpoint(i, SetpointKind.ACCEL_XY_POS_Z, np.append(a, 0.0), float(z_ned),
                             yaw)

    # -- telemetry ----------------------------------------------------------------------------

    def mode(self, i: int) -> SimMode:
        """Current mode of vehicle ``i``."""
        return SimMode(int(self.state.mode[self._index(i)]))

    @property
    def modes(self) -> tuple[SimMode, ...]:
        """Current mode of every vehicle."""
        return tuple(SimMode(int(m)) for m in self.state.mode)

    @property
    def armed(self) -> np.ndarray:
        """(N,) bool, rotors enabled."""
        return self.state.mode != SimMode.DISARMED

    @property
    def p_ned(self) -> np.ndarray:
        """(N, 3) position estimate, m (copy)."""
        return self.state.p_est.copy()

    @property
    def v_ned(self) -> np.ndarray:
        """(N, 3) velocity estimate, m/s (copy)."""
        return self.state.v_est.copy()

    @property
    def q_wxyz(self) -> np.ndarray:
        """(N, 4) attitude estimate (copy)."""
        return self.state.q_est.copy()

    @property
    def euler(self) -> np.ndarray:
        """(N, 3) estimated roll, pitch, yaw, rad."""
        return euler_from_quaternions(self.state.q_est)

    @property
    def accel_ref_ned(self) -> np.ndarray:
        """(N, 3) acceleration reference nu_a used in the last step, m/s^2 (copy)."""
        return self.state.accel_ref_ned.copy()

    @property
    def attitude_cmd(self) -> np.ndarray:
        """(N, 3) commanded roll, pitch, yaw of the last step, rad (copy)."""
        return self.state.attitude_cmd.copy()

    @property
    def thrust_cmd(self) -> np.ndarray:
        """(N,) commanded total thrust of the last step, N (copy)."""
        return self.state.thrust_cmd.copy()

    # -- helpers ------------------------------------------------------------------------------

    def _index(self, i: int) -> int:
        i = operator.index(i)
        if not 0 <= i < self.n_vehicles:
            raise IndexError(f"vehicle index {i} outside 0..{self.n_vehicles - 1}")
        return i

    def _in_flight(self, i: int) -> bool:
        s = self.state
        return bool(s.mode[i] != SimMode.DISARMED
                    and s.z_home[i] - s.p_est[i, 2] >= self._configs[i].ground_clearance)

    def _store_setpoint(self, i: int, kind: SetpointKind, accel_ned: np.ndarray, z_ned: float,
                        yaw: float | None) -> None:
        if yaw is not None and not math.isfinite(yaw):
            raise ValueError(f"yaw must be finite, got {yaw}")
        s = self.state
        s.sp_kind[i] = int(kind)
        s.sp_accel_ned[i] = accel_ned
        s.sp_z_ned[i] = z_ned
        s.sp_yaw[i] = math.nan if yaw is None else float(yaw)
        s.sp_time[i] = self.t


def _finite_vector(value: np.ndarray | tuple[float, ...], size: int, name: str) -> np.ndarray:
    a = np.asarray(value, dtype=np.float64)
    if a.shape != (size,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be {size} finite numbers, got {value!r}")
    return a


def _load_mode_entries() -> None:
    """Compile or load the mode entries the commands call, now, on a scratch vehicle.

    Called from Python, each would be compiled at its first use: at the first arm,
    take-off, offboard and landing the simulator would stand still (cold cache: figures
    in docs/performance.md) and every vehicle's telemetry would go stale at each phase
    change.
    """
    scratch = make_autopilot_state(1)
    enter_armed_hold(scratch, 0)
    enter_takeoff(scratch, 0, 1.0)
    enter_offboard(scratch, 0)
    enter_hold(scratch, 0)
    enter_land(scratch, 0)
    enter_disarmed(scratch, 0)
