"""Eq. udi per vehicle against the paper: its stacked form, the steady centripetal
acceleration, saturation, the sticks, the compiled kernel, each vehicle's own frame."""

from __future__ import annotations

import numpy as np
import pytest

from gcs.config import load_team
from gcs.formation._motion import edges_to_slots
from gcs.guidance import Guidance, MotionDemand
from gcs.guidance._law import formation_acceleration, relative_measurements, saturate
from gcs.guidance._udi import to_ned_saturated
from tests.support.double_integrator import yaw_rotations
from tests.support.paths import SQUARE, TEAMS


@pytest.mark.parametrize("config", TEAMS)
def test_kernel_is_eq_udi_in_stacked_form(config: str) -> None:
    """Per-vehicle kernel (lead 0) == u = -c1 v - c2 Bbar D_z D_ztilde e + Abar D_ztilde z."""
    team = load_team(config)
    f = team.formation
    g = Guidance.from_team(team)
    rng = np.random.default_rng(1)
    p = f.positions + rng.normal(0, 0.15, f.positions.shape)
    v = rng.normal(0, 0.5, p.shape)
    c1, c2 = g.c1, g.c2
    A = c1 * g.basis.velocity_matrix(0.3, 0.1, 0.2, 1.0)  # any A on the vehicles' own edges
    z = f.relative(p)
    nz = np.linalg.norm(z, axis=1)
    e = nz - f.distances
    unit = z / nz[:, None]
    stacked = -c1 * v - c2 * f.incidence @ (unit * e[:, None]) + A @ unit
    nb = f.slot_neighbour
    rel_p = (p[nb] - p[:, None]) * f.slot_mask[..., None]
    rel_v = (v[nb] - v[:, None]) * f.slot_mask[..., None]
    half = edges_to_slots(f, A) / 2  # A split in any way between the two feed-forwards
    u = formation_acceleration(v, rel_p, rel_v, f.slot_mask, f.distances[f.slot_edge],
                               half, half, c1=c1, c2=c2, lead=0.0)
    np.testing.assert_allclose(u, stacked, atol=1e-12)


def test_steady_state_acceleration_is_the_centripetal_one() -> None:
    """At the desired shape moving at v*, eq. udi commands exactly the rigid motion's accel."""
    team = load_team(SQUARE)
    g = Guidance.from_team(team)
    f = g.formation
    demand = MotionDemand(rotate=1.0)
    omega = g.angular_rate(demand)
    v = g.basis.desired_velocities(g.velocity_matrix(demand))
    yaw = np.zeros(f.n)
    # The held command is the one of half a period ahead: the team has turned by
    # atan(omega T / 2) along its predicted (linear) path.
    turn = np.arctan(omega * g.lead)
    R = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    u = g.accelerations(f.positions, v, yaw, demand)
    np.testing.assert_allclose(u, -omega**2 * f.positions @ R.T, atol=1e-12)
    g.lead = 0.0  # plain eq. udi: exactly the centripetal acceleration now
    u = g.accelerations(f.positions, v, yaw, demand)
    np.testing.assert_allclose(u, -omega**2 * f.positions, atol=1e-12)


@pytest.mark.parametrize("config", TEAMS)
def test_a_spin_started_from_rest_does_not_pull_the_shape_in(config: str) -> None:
    """Turn compensation: a team at rest in its shape, told to spin, accelerates along the
    spin only (eq. udi alone adds the full centripetal pull, -omega^2 r, before it turns)."""
    g = Guidance.from_team(load_team(config))
    f = g.formation
    g.lead = 0.0
    demand = MotionDemand(rotate=1.0)
    omega = g.angular_rate(demand)
    desired = g.basis.desired_velocities(g.velocity_matrix(demand))
    at_rest, yaw = np.zeros((f.n, 2)), np.zeros(f.n)
    assert g.turn_compensation  # the shipped teams fly with it
    u = g.accelerations(f.positions, at_rest, yaw, demand)
    np.testing.assert_allclose(u, saturate(g.c1 * desired, norm_max=g.accel_norm,
                                           axis_max=g.accel_axis), atol=1e-12)
    g.turn_compensation = False
    u = g.accelerations(f.positions, at_rest, yaw, demand)
    centred = f.positions - f.positions.mean(axis=0)
    paper = g.c1 * desired - omega**2 * centred
    np.testing.assert_allclose(u, saturate(paper, norm_max=g.accel_norm,
                                           axis_max=g.accel_axis), atol=1e-12)


@pytest.mark.parametrize("config", TEAMS)
def test_a_spin_stopped_keeps_the_centripetal_pull_of_the_turn_the_team_still_makes(
        config: str) -> None:
    """Turn compensation: a team in its shape still spinning at the rate it was told,
    told to stop, is slowed along its motion and still pulled in as its turn needs
    (eq. udi alone drops the pull at once, and the team widens)."""
    g = Guidance.from_team(load_team(config))
    f = g.formation
    g.lead = 0.0
    spinning = g.basis.desired_velocities(g.velocity_matrix(MotionDemand(rotate=1.0)))
    omega = g.angular_rate(MotionDemand(rotate=1.0))
    centred = f.positions - f.positions.mean(axis=0)
    yaw = np.zeros(f.n)
    u = g.accelerations(f.positions, spinning, yaw, MotionDemand())
    expected = -g.c1 * spinning - omega**2 * centred
    np.testing.assert_allclose(u, saturate(expected, norm_max=g.accel_norm,
                                           axis_max=g.accel_axis), atol=1e-9)
    g.turn_compensation = False
    u = g.accelerations(f.positions, spinning, yaw, MotionDemand())
    np.testing.assert_allclose(u, saturate(-g.c1 * spinning, norm_max=g.accel_norm,
                                           axis_max=g.accel_axis), atol=1e-9)


def test_saturation_in_norm_then_per_axis() -> None:
    u = np.array([[3.0, 0.0], [2.0, 2.0], [0.1, -0.2], [-1.0, 1.8]])
    s = saturate(u, norm_max=2.18, axis_max=1.54)
    assert np.all(np.linalg.norm(s, axis=1) <= 2.18 + 1e-12)
    assert np.all(np.abs(s) <= 1.54 + 1e-12)
    np.testing.assert_allclose(s[2], u[2])  # small commands pass unchanged
    np.testing.assert_allclose(s[1], [1.54, 1.54])  # direction kept at 45 degrees
    assert s[0, 0] == pytest.approx(1.54)


def test_motion_demand_rejects_out_of_range_sticks() -> None:
    with pytest.raises(ValueError, match="forward"):
        MotionDemand(forward=1.5)
    with pytest.raises(ValueError, match="scale"):
        MotionDemand(scale=0.0)


def test_diagonal_stick_is_not_faster() -> None:
    g = Guidance.from_team(load_team(SQUARE))
    v = g.basis.desired_velocities(g.velocity_matrix(MotionDemand(forward=1.0, right=1.0)))
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), g.max_speed)


def reference_udi(v_own: np.ndarray, rel_p: np.ndarray, rel_v: np.ndarray, mask: np.ndarray,
                  d: np.ndarray, alpha_v: np.ndarray, alpha_a: np.ndarray, c1: float, c2: float,
                  lead: float, omega: float = 0.0, turning: bool = False) -> np.ndarray:
    """Eq. udi with the hold compensation and the turn compensation as array expressions
    (the compiled kernel's spec)."""
    q, q_rate = -rel_p, -rel_v
    dist = np.linalg.norm(q, axis=2)
    unit = np.divide(q, dist[..., None], out=np.zeros_like(q), where=mask[..., None])
    e = (dist - d + lead * np.einsum("isk,isk->is", unit, q_rate)) * mask
    ahead = q + lead * q_rate
    unit_ahead = np.divide(ahead, np.linalg.norm(ahead, axis=2)[..., None],
                           out=np.zeros_like(q), where=mask[..., None])
    desired = np.einsum("is,isk->ik", alpha_v, unit) / c1
    rate = np.divide(q[..., 0] * q_rate[..., 1] - q[..., 1] * q_rate[..., 0], dist**2,
                     out=np.zeros_like(dist), where=mask)
    w = rate.sum(axis=1) / mask.sum(axis=1)  # each vehicle's edges' mean turn rate

    def z_cross(a: np.ndarray) -> np.ndarray:  # z x a about down, in the plane
        return np.column_stack((-a[:, 1], a[:, 0]))
    turn = w[:, None] * z_cross(v_own) - omega * z_cross(desired) if turning else 0.0
    return (-c1 * v_own + c1 * desired + turn
            + np.einsum("is,isk->ik", alpha_a - c2 * e, unit_ahead))


@pytest.mark.parametrize("config", TEAMS)
def test_compiled_guidance_matches_the_law_written_as_arrays(config: str) -> None:
    """Hold-compensated eq. udi in each vehicle's frame, rotated back to NED and saturated."""
    team = load_team(config)
    g = Guidance.from_team(team)
    f = g.formation
    rng = np.random.default_rng(7)
    for _ in range(20):
        p = f.positions * rng.uniform(0.8, 1.2) + rng.normal(0, 0.15, f.positions.shape) + 5.0
        v = rng.normal(0, 0.5, (f.n, 2))
        yaw = rng.uniform(-np.pi, np.pi, f.n)
        demand = MotionDemand(*rng.uniform(-1, 1, 3), scale=float(rng.uniform(0.8, 1.2)))
        alpha_v, alpha_a, d = g.coefficients(demand)
        rot = yaw_rotations(-yaw)  # what each vehicle senses is in its own frame
        nb, mask = f.slot_neighbour, f.slot_mask
        rel_p = np.einsum("ikl,isl->isk", rot, (p[nb] - p[:, None]) * mask[..., None])
        rel_v = np.einsum("ikl,isl->isk", rot, (v[nb] - v[:, None]) * mask[..., None])
        v_own = np.einsum("ikl,il->ik", rot, v)
        omega = g.angular_rate(demand)
        assert g.turn_compensation
        local = reference_udi(v_own, rel_p, rel_v, mask, d, alpha_v, alpha_a, g.c1, g.c2, g.lead,
                              omega, turning=True)
        np.testing.assert_allclose(
            formation_acceleration(v_own, rel_p, rel_v, mask, d, alpha_v, alpha_a, c1=g.c1,
                                   c2=g.c2, lead=g.lead, omega=omega, turn_compensation=True),
            local, atol=1e-12)
        ned = np.einsum("ilk,il->ik", rot, local)  # rotation back by +yaw
        expected = saturate(ned, norm_max=g.accel_norm, axis_max=g.accel_axis)
        np.testing.assert_allclose(g.accelerations(p, v, yaw, demand), expected, atol=1e-12)
        assert np.linalg.norm(expected, axis=1).max() <= g.accel_norm + 1e-12


@pytest.mark.parametrize("config", TEAMS)
def test_compiled_distance_errors_are_the_norms_of_the_edge_vectors(config: str) -> None:
    formation = load_team(config).formation
    rng = np.random.default_rng(3)
    for scale in (0.7, 1.0, 1.3):
        p = rng.normal(0, 2, (formation.n, 3))[:, :2]  # a strided view, as the loop passes
        z = formation.relative(p)
        assert formation.distance_errors(p, scale) == pytest.approx(
            np.linalg.norm(z, axis=1) - scale * formation.distances)


@pytest.mark.parametrize("config", TEAMS)
def test_each_vehicle_senses_in_its_own_frame_and_commands_go_back_by_its_yaw(
        config: str) -> None:
    """rel_p[i, s] = R(-yaw_i)(p_j - p_i), likewise v_i and v_j - v_i; NED = R(yaw_i) local.

    Eq. udi is rotation-equivariant: fed NED data and returning its command
    unrotated, the guidance sends the same physical accelerations, so no test of
    the closed loop or of invariance sees a dropped rotation. This one does.
    """
    g = Guidance.from_team(load_team(config))
    f = g.formation
    rng = np.random.default_rng(5)
    p = rng.normal(0, 2.0, (f.n, 3))  # NED with altitude, as telemetry has it
    v = rng.normal(0, 1.0, (f.n, 3))
    yaw = rng.permutation(np.linspace(0.3, 2.8, f.n))  # distinct, none 0 or pi
    meas = relative_measurements(f, p, v, yaw)
    to_own = yaw_rotations(-yaw)
    for i in range(f.n):
        np.testing.assert_allclose(meas.v_own[i], to_own[i] @ v[i, :2], rtol=0, atol=1e-12)
        for s in range(f.slot_mask.shape[1]):
            if not f.slot_mask[i, s]:
                assert not meas.rel_p[i, s].any() and not meas.rel_v[i, s].any()
                continue
            tail, head = f.edges[f.slot_edge[i, s]]
            j = head if tail == i else tail  # the neighbour, from the edge list
            np.testing.assert_allclose(meas.rel_p[i, s], to_own[i] @ (p[j, :2] - p[i, :2]),
                                       rtol=0, atol=1e-12)
            np.testing.assert_allclose(meas.rel_v[i, s], to_own[i] @ (v[j, :2] - v[i, :2]),
                                       rtol=0, atol=1e-12)
    assert f.slot_mask.sum() == 2 * f.m  # every edge seen from both ends

    u = rng.normal(0, 1.0, (f.n, 2))  # any command in the vehicles' frames, unlimited
    to_ned = yaw_rotations(yaw)
    np.testing.assert_allclose(to_ned_saturated(u, yaw, np.inf, np.inf),
                               np.einsum("ikl,il->ik", to_ned, u), rtol=0, atol=1e-12)
    demand = MotionDemand(forward=0.4, rotate=0.3)  # and through the guidance, unsaturated
    near = np.c_[f.positions + rng.normal(0, 0.05, f.positions.shape), np.zeros(f.n)]
    local = g.local(relative_measurements(f, near, 0.1 * v, yaw), demand)
    assert np.abs(local).max() < g.accel_axis / 2
    np.testing.assert_allclose(g.accelerations(near[:, :2], 0.1 * v[:, :2], yaw, demand),
                               np.einsum("ikl,il->ik", to_ned, local), rtol=0, atol=1e-12)


def test_a_vehicle_facing_east_sees_north_on_its_left_and_forward_is_east() -> None:
    """The sign of the frames, in NED (x north, y east, yaw clockwise from north)."""
    f = load_team(SQUARE).formation
    east = np.full(f.n, np.pi / 2)
    p = np.zeros((f.n, 2))
    p[f.slot_neighbour[0, 0]] = [1.0, 0.0]  # vehicle 0's first neighbour 1 m north of it
    meas = relative_measurements(f, p, np.zeros((f.n, 2)), east)
    np.testing.assert_allclose(meas.rel_p[0, 0], [0.0, -1.0], atol=1e-12)  # left: -y (body)
    forward = np.tile([1.0, 0.0], (f.n, 1))
    np.testing.assert_allclose(to_ned_saturated(forward, east, np.inf, np.inf),
                               np.tile([0.0, 1.0], (f.n, 1)), atol=1e-12)  # east
