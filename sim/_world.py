"""The simulated world: N quadrotors on ropes to one payload, ground, wind, sensors.

Build it from configs and explicit arrays, advance it with fixed rotor commands
(:meth:`World.step`) or in lockstep with the onboard autopilots
(:meth:`World.run`), and read the true state and the latest sensor samples.
Calls block until the simulated time has been computed; nothing runs in the
background.
"""

from __future__ import annotations

import math

import numpy as np

from sim._config import WorldConfig
from sim._physics import run_lockstep, run_physics, samples_in
from sim._state import PhysicsParams, PhysicsState, make_physics_params, make_physics_state
from vehicles import Airframe, Autopilot, Measurements, make_measurements

__all__ = ["World"]

_CHUNK_PHYSICS_STEPS = 8192
"""Largest number of physics steps per compiled call (bounds the noise buffers)."""


class World:
    """Physics of a team of identical quadrotors carrying one point-mass payload.

    Arguments (all keyword-only):
        airframe: the true airframe of every vehicle.
        config: world configuration (rates, ropes, ground, wind, sensors).
        p0_ned: (N, 3) start positions of the vehicles' centres of mass, m.
            With ``z = config.ground.z_ned`` they start resting on the ground.
        rope_length: (N,) rope length of each vehicle, m.
        payload_mass: payload mass, kg.
        payload_p0_ned: (3,) payload start position, m.
        rng: seeded generator; all sensor noise and gusts derive from it.
        yaw0: (N,) start headings, rad (default all zero: nose north).
    """

    def __init__(self, *, airframe: Airframe, config: WorldConfig, p0_ned: np.ndarray,
                 rope_length: np.ndarray, payload_mass: float, payload_p0_ned: np.ndarray,
                 rng: np.random.Generator, yaw0: np.ndarray | None = None) -> None:
        p0 = np.array(p0_ned, dtype=np.float64)
        if p0.ndim != 2 or p0.shape[1] != 3 or p0.shape[0] < 1 or not np.all(np.isfinite(p0)):
            raise ValueError(f"p0_ned must be finite with shape (N, 3), got shape {p0.shape}")
        n = p0.shape[0]
        ropes = np.array(rope_length, dtype=np.float64)
        if ropes.shape != (n,) or not np.all(ropes > 0.0) or not np.all(np.isfinite(ropes)):
            raise ValueError(f"rope_length must be {n} positive lengths, got {rope_length!r}")
        if not payload_mass > 0.0 or not math.isfinite(payload_mass):
            raise ValueError(f"payload_mass must be positive, got {payload_mass}")
        payload_p0 = np.array(payload_p0_ned, dtype=np.float64)
        if payload_p0.shape != (3,) or not np.all(np.isfinite(payload_p0)):
            raise ValueError(f"payload_p0_ned must be 3 finite numbers, got {payload_p0_ned!r}")
        yaw = np.zeros(n) if yaw0 is None else np.array(yaw0, dtype=np.float64)
        if yaw.shape != (n,) or not np.all(np.isfinite(yaw)):
            raise ValueError(f"yaw0 must be {n} finite angles, got {yaw0!r}")
        self.airframe = airframe
        self.config = config
        self.state: PhysicsState = make_physics_state(p0, yaw, payload_p0)
        self.params: PhysicsParams = make_physics_params(airframe, config, ropes,
                                                         float(payload_mass))
        self._measurements = make_measurements(n)
        self._gust_rng, self._imu_rng, self._pose_rng = rng.spawn(3)

    # -- stepping -----------------------------------------------------------------------------

    @property
    def n_vehicles(self) -> int:
        """Number of vehicles."""
        return int(self.state.p_ned.shape[0])

    @property
    def physics_rate_hz(self) -> float:
        """Integration rate, Hz."""
        return self.config.physics_rate_hz

    @property
    def t(self) -> float:
        """Simulated time, s."""
        return int(self.state.step[0]) / self.config.physics_rate_hz

    def step(self, rotor_speed_cmd: np.ndarray, duration: float) -> None:
        """Advance ``duration`` s (a whole number of physics steps) holding the rotor
        speed commands (N, 4) in rad/s."""
        cmd = np.array(rotor_speed_cmd, dtype=np.float64)
        if cmd.shape != (self.n_vehicles, 4) or not np.all(np.isfinite(cmd)):
            raise ValueError(f"rotor_speed_cmd must be finite with shape ({self.n_vehicles}, 4)")
        remaining = _whole_steps(duration, self.physics_rate_hz, "duration")
        while remaining > 0:
            n = min(remaining, _CHUNK_PHYSICS_STEPS)
            gust, imu, pose = self._draw_noise(n)
            run_physics(self.state, self.params, self._measurements, cmd, n, gust, imu, pose)
            remaining -= n

    def run(self, autopilot: Autopilot, duration: float) -> None:
        """Advance ``duration`` s with ``autopilot`` closing the loop at its own rate.

        Each control period the autopilot reads the latest measurements and
        sets rotor commands, then the physics integrates that period. Commands
        and setpoints given to the autopilot between calls act from the next
        control period on.
        """
        if autopilot.n_vehicles != self.n_vehicles:
            raise ValueError(f"autopilot has {autopilot.n_vehicles} vehicles, world has "
                             f"{self.n_vehicles}")
        substeps = _whole_steps(1.0 / autopilot.rate_hz, self.physics_rate_hz,
                                "the autopilot period")
        remaining = _whole_steps(duration, autopilot.rate_hz, "duration")
        per_chunk = max(1, _CHUNK_PHYSICS_STEPS // substeps)
        while remaining > 0:
            n = min(remaining, per_chunk)
            gust, imu, pose = self._draw_noise(n * substeps)
            run_lockstep(self.state, self.params, self._measurements, autopilot.state,
                         autopilot.params, n, substeps, gust, imu, pose)
            remaining -= n

    # -- sensors ------------------------------------------------------------------------------

    def measurements(self) -> Measurements:
        """Latest sensor samples (live arrays, updated in place by stepping; copy to keep).

        ``pose_seq`` stays 0 until the first motion-capture sample."""
        return self._measurements

    # -- true state (copies) ------------------------------------------------------------------

    @property
    def p_ned(self) -> np.ndarray:
        """(N, 3) vehicle positions, m."""
        return self.state.p_ned.copy()

    @property
    def v_ned(self) -> np.ndarray:
        """(N, 3) vehicle velocities, m/s."""
        return self.state.v_ned.copy()

    @property
    def q_wxyz(self) -> np.ndarray:
        """(N, 4) vehicle attitudes R_ned_body."""
        return self.state.q_wxyz.copy()

    @property
    def omega_body(self) -> np.ndarray:
        """(N, 3) body rates, rad/s."""
        return self.state.omega_body.copy()

    @property
    def rotor_speed(self) -> np.ndarray:
        """(N, 4) rotor speeds, rad/s."""
        return self.state.rotor_speed.copy()

    @property
    def payload_p_ned(self) -> np.ndarray:
        """(3,) payload position, m."""
        return self.state.payload_p_ned.copy()

    @property
    def payload_v_ned(self) -> np.ndarray:
        """(3,) payload velocity, m/s."""
        return self.state.payload_v_ned.copy()

    @property
    def rope_tension(self) -> np.ndarray:
        """(N,) rope tensions of the last physics step, N."""
        return self.state.rope_tension.copy()

    @property
    def specific_force_body(self) -> np.ndarray:
        """(N, 3) noise-free specific force in body FRD, m/s^2."""
        return self.state.specific_force_body.copy()

    @property
    def wind_ned(self) -> np.ndarray:
        """(3,) current wind velocity (mean plus gust), m/s."""
        return self.params.wind_mean + self.state.gust_ned

    # -- helpers ------------------------------------------------------------------------------

    def _draw_noise(self, n_steps: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        first = int(self.state.step[0])
        n = self.n_vehicles
        imu = samples_in(first, n_steps, self.params.imu_every)
        pose = samples_in(first, n_steps, self.params.pose_every)
        return (self._gust_rng.standard_normal((n_steps, 3)),
                self._imu_rng.standard_normal((imu, n, 6)),
                self._pose_rng.standard_normal((pose, n, 9)))


def _whole_steps(duration: float, rate_hz: float, what: str) -> int:
    steps = duration * rate_hz
    n = round(steps)
    if n < 0 or abs(steps - n) > 1e-6 * max(1.0, steps):
        raise ValueError(f"{what} ({duration} s) must be a non-negative whole number of "
                         f"{1.0 / rate_hz:g} s steps")
    return n
