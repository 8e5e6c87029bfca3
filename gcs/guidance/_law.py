"""Formation-motion guidance: eq. udi of the paper, per vehicle, from relative data.

Each vehicle's acceleration is computed from what it could sense itself: its own
velocity and the relative positions (and relative velocities) of its neighbours,
all expressed in its own frame. The kernel never sees an absolute position, so
translating the team or rotating one vehicle's frame changes no physical
acceleration (tested).

Sample-and-hold compensation. The GCS runs the guidance at 4 Hz and each
vehicle holds the acceleration until the next tick. With the paper's gains a
zero-order hold at 4 Hz destabilises the stiffest shape mode of a plain double
integrator (for the square, c2 * lambda_max * T / 2 = 0.275 > c1 = 0.17: that
mode grows with a time constant of about 19 s), and the held feed-forward of a
spinning team lags its rotation (started on the rigid spin, the square turns
about 15 % too fast while its shape error grows from 3 cm; from rest it ends
turning about twice as fast, 2 m out of shape, held only by the saturation).
So eq. udi is evaluated at the relative positions predicted half
a period ahead: the edge directions along ``p_i - p_j + (T/2)(v_i - v_j)`` and
the distance errors to first order, ``e_k + (T/2) d||z_k||/dt`` (which is zero
in rigid motion). The hold's average delay is cancelled. An autopilot that
follows a setpoint late (``guidance.setpoint_lag``) lengthens the prediction by its
lag.

Turn compensation. Eq. udi's acceleration feed-forward ``A_a z`` is the
acceleration of the commanded rigid motion, ``omega z x v_desired`` for a spin.
When the operator starts a spin the team is not turning yet: its velocity
reaches the commanded one only at the rate c1 (a 6 s time constant with the
paper's gains), but the full centripetal pull acts at once, and the shape
shrinks (by 0.13 m on the square at 0.4 rad/s, the worst moment of the paper
flight; 0.16 m on ArduCopter SITL). When the spin stops, the team still turns
but the pull is gone, and the shape widens. With ``guidance.turn_compensation``
the spin's part of the feed-forward is the centripetal acceleration of the
motion the vehicle makes: ``w z x v_i - omega z x v_desired`` is added, ``w``
the mean turn rate of its edges, ``(q x q')/||q||^2``, from the same relative
measurements. In a rigid spin at the commanded rate it is zero; its turning
part is perpendicular to the vehicle's velocity and never speeds it up. With
``lead = 0`` and no turn compensation the kernel is exactly eq. udi.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gcs.config import Team
from gcs.formation import Formation, MotionBasis, motion_basis
from gcs.guidance._udi import local_frames, to_ned_saturated, udi

__all__ = [
    "Guidance",
    "MotionDemand",
    "RelativeMeasurements",
    "formation_acceleration",
    "relative_measurements",
    "saturate",
]


def formation_acceleration(
    v_own: np.ndarray,
    rel_p: np.ndarray,
    rel_v: np.ndarray,
    mask: np.ndarray,
    d: np.ndarray,
    alpha_v: np.ndarray,
    alpha_a: np.ndarray,
    *,
    c1: float,
    c2: float,
    lead: float,
    omega: float = 0.0,
    turn_compensation: bool = False,
) -> np.ndarray:
    """Eq. udi for every vehicle, each in its own frame (compiled: :func:`gcs.guidance._udi.udi`).

    Per edge slot, with ``q = p_i - p_j`` and its rate, the distance error is
    predicted ``lead`` ahead to first order, ``e = ||q|| - d + lead q.q'/||q||``,
    and the vehicle commands ``-c1 v_i + alpha_v q/||q|| + (alpha_a - c2 e)
    q_ahead/||q_ahead||`` summed over its edges, ``q_ahead = q + lead q'``.

    Args:
        v_own: (n, 2) own velocity, m/s.
        rel_p: (n, S, 2) neighbour positions relative to the vehicle, p_j - p_i, m.
        rel_v: (n, S, 2) neighbour velocities relative to the vehicle, v_j - v_i, m/s.
        mask: (n, S) which slots hold a neighbour.
        d: (n, S) desired distance of each slot's edge, m.
        alpha_v: (n, S) velocity feed-forward ``c1 A_v`` on the vehicle's edges
            (multiplying the unit vector from neighbour to vehicle), m/s^2.
        alpha_a: (n, S) acceleration feed-forward ``A_a`` on the same edges, m/s^2.
            Eq. udi's ``A`` is ``alpha_v + alpha_a``; they are split because the
            velocity feed-forward must meet the velocity measured at the same
            instant (they cancel in steady motion) while the acceleration is the
            one of mid-hold.
        c1: velocity gain, 1/s. c2: distance gain, 1/s^2.
        lead: prediction horizon of the distance errors, s (half the guidance period).
        omega: the team's commanded angular rate about down, rad/s (the turn
            compensation's; eq. udi has it in ``alpha_a``).
        turn_compensation: the feed-forward of the turn the vehicle's edges make rather
            than of the commanded one (module doc); False is eq. udi.

    Returns:
        (n, 2) commanded acceleration, m/s^2, in each vehicle's frame.
    """
    return udi(_f64(v_own), _f64(rel_p), _f64(rel_v), np.ascontiguousarray(mask, dtype=bool),
               _f64(d), _f64(alpha_v), _f64(alpha_a), float(c1), float(c2), float(lead),
               float(omega), bool(turn_compensation))


def saturate(u: np.ndarray, *, norm_max: float, axis_max: float) -> np.ndarray:
    """Limit each (n, 2) acceleration in norm (keeping its direction), then per axis."""
    u = _f64(u)
    return to_ned_saturated(u, np.zeros(len(u)), float(norm_max), float(axis_max))


def _f64(a: np.ndarray) -> np.ndarray:
    """float64 in C order: the one layout the kernels are compiled for."""
    return np.ascontiguousarray(a, dtype=np.float64)


@dataclass(frozen=True)
class RelativeMeasurements:
    """What each vehicle senses, in its own frame (yaw-rotated NED)."""

    v_own: np.ndarray
    rel_p: np.ndarray
    rel_v: np.ndarray


def relative_measurements(formation: Formation, p_ned: np.ndarray, v_ned: np.ndarray,
                          yaw: np.ndarray) -> RelativeMeasurements:
    """Relative positions/velocities of each vehicle's neighbours in its own frame.

    The GCS has NED telemetry; this is the one place that turns it into the
    relative, local data the guidance law is defined on.
    """
    v_own, rel_p, rel_v = local_frames(_f64(p_ned[:, :2]), _f64(v_ned[:, :2]), _f64(yaw),
                                       formation.slot_neighbour, formation.slot_mask)
    return RelativeMeasurements(v_own=v_own, rel_p=rel_p, rel_v=rel_v)


@dataclass(frozen=True)
class MotionDemand:
    """The operator's demand on the super-vehicle.

    ``forward``/``right`` move along the team's body axes and ``rotate`` spins it
    about the centroid (positive clockwise seen from above); each in [-1, 1] of
    the configured maximum. ``scale`` multiplies the desired distances.
    """

    forward: float = 0.0
    right: float = 0.0
    rotate: float = 0.0
    scale: float = 1.0

    def __post_init__(self) -> None:
        for name in ("forward", "right", "rotate"):
            value = getattr(self, name)
            if not -1.0 <= value <= 1.0:
                raise ValueError(f"MotionDemand.{name} must be in [-1, 1], got {value}")
        if not self.scale > 0.0:
            raise ValueError(f"MotionDemand.scale must be positive, got {self.scale}")


class Guidance:
    """Eq. udi for one team: gains, motion synthesis and saturation from the config.

    Args:
        formation: the desired shape.
        c1, c2: gains of eq. udi.
        max_speed: translation speed at full stick, m/s.
        max_rotation_disagreement: largest rotation disagreement mu_r at full stick, m/s.
        period: guidance period, s (sets the hold compensation).
        accel_norm, accel_axis: saturation of the commanded acceleration, m/s^2.
        hold_compensation: predict distance errors half a period ahead (see module doc).
        setpoint_lag: the autopilots' lag in following a setpoint, s: added to the
            prediction.
        turn_compensation: the spin's feed-forward of the turn the edges make (module doc).
    """

    def __init__(self, formation: Formation, *, c1: float, c2: float, max_speed: float,
                 max_rotation_disagreement: float, period: float, accel_norm: float,
                 accel_axis: float, hold_compensation: bool = True,
                 setpoint_lag: float = 0.0, turn_compensation: bool = True) -> None:
        self.formation = formation
        self.basis: MotionBasis = motion_basis(formation)
        self.c1, self.c2 = float(c1), float(c2)
        self.max_speed = max_speed
        self.max_rotation_disagreement = max_rotation_disagreement
        self.period = period
        self.accel_norm, self.accel_axis = accel_norm, accel_axis
        self.lead = (0.5 * float(period) if hold_compensation else 0.0) + float(setpoint_lag)
        self.turn_compensation = turn_compensation
        self._mask = np.ascontiguousarray(formation.slot_mask, dtype=bool)
        self._coefficients: tuple[MotionDemand, tuple[np.ndarray, np.ndarray, np.ndarray]] \
            | None = None
        # Load the compiled kernels now: the first call loads (or compiles) them, which
        # the loop's first tick must not wait for (it would come late to every vehicle).
        n = formation.n
        self.accelerations(formation.positions, np.zeros((n, 2)), np.zeros(n), MotionDemand())

    @classmethod
    def from_team(cls, team: Team) -> Guidance:
        """The guidance a team config describes."""
        g, lim = team.config.guidance, team.config.limits
        return cls(team.formation, c1=g.c1, c2=g.c2, max_speed=g.max_speed,
                   max_rotation_disagreement=g.max_rotation_disagreement,
                   period=1.0 / g.rate_hz, accel_norm=lim.accel_norm,
                   accel_axis=lim.accel_axis, hold_compensation=g.hold_compensation,
                   setpoint_lag=g.setpoint_lag, turn_compensation=g.turn_compensation)

    def velocity_matrix(self, demand: MotionDemand) -> np.ndarray:
        """A_v (n, m) of a demand: the stick values multiply the unit motions."""
        speed = np.array([demand.forward, demand.right]) * self.max_speed
        norm = float(np.linalg.norm(speed))
        if norm > self.max_speed:  # a diagonal stick is not faster than a straight one
            speed *= self.max_speed / norm
        omega = self.angular_rate(demand)
        return self.basis.velocity_matrix(speed[0], speed[1], omega, demand.scale)

    def angular_rate(self, demand: MotionDemand) -> float:
        """Commanded angular rate of the team about its centroid, rad/s."""
        return self.basis.angular_rate(demand.rotate * self.max_rotation_disagreement,
                                       demand.scale)

    def coefficients(self, demand: MotionDemand) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Slot coefficients ``alpha_v``, ``alpha_a`` and desired distances ``d`` (n, S).

        They depend on the demand only, which the operator holds for many ticks:
        the latest are kept (computing them is much of the guidance's cost for a
        hundred vehicles: docs/performance.md).
        """
        cached = self._coefficients
        if cached is not None and cached[0] == demand:
            return cached[1]
        f = self.formation
        alpha_v, alpha_a = self.basis.guidance_coefficients(self.velocity_matrix(demand),
                                                            self.c1, demand.scale)
        d = demand.scale * f.distances[f.slot_edge] * f.slot_mask
        coefficients = (_f64(alpha_v), _f64(alpha_a), _f64(d))  # the kernel's layout, once
        self._coefficients = (demand, coefficients)
        return coefficients

    def local(self, meas: RelativeMeasurements, demand: MotionDemand) -> np.ndarray:
        """Unsaturated acceleration (n, 2) in each vehicle's frame.

        :func:`formation_acceleration` on arrays already in the kernel's layout
        (cached coefficients; ``meas`` as :func:`relative_measurements` gives it:
        float64, C order): the tick skips ten layout checks.
        """
        alpha_v, alpha_a, d = self.coefficients(demand)
        return udi(meas.v_own, meas.rel_p, meas.rel_v, self._mask, d, alpha_v, alpha_a,
                   self.c1, self.c2, self.lead, self.angular_rate(demand),
                   self.turn_compensation)

    def accelerations(self, p_ned: np.ndarray, v_ned: np.ndarray, yaw: np.ndarray,
                      demand: MotionDemand) -> np.ndarray:
        """Saturated horizontal acceleration setpoints (n, 2) in NED, m/s^2."""
        meas = relative_measurements(self.formation, p_ned, v_ned, yaw)
        return to_ned_saturated(self.local(meas, demand), _f64(yaw), self.accel_norm,
                                self.accel_axis)
