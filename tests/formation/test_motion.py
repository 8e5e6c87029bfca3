"""Motion synthesis against the paper: the disagreements that give each motion of the
team, and the centripetal term of Proposition 1."""

from __future__ import annotations

import numpy as np
import pytest

from gcs.config import load_team
from gcs.formation import motion_basis
from gcs.formation._motion import centripetal_matrix
from tests.support.paths import SQUARE, TEAMS


@pytest.mark.parametrize("config", TEAMS)
def test_translation_disagreements_reproduce_velocity(config: str) -> None:
    f = load_team(config).formation
    basis = motion_basis(f)
    for A, want in ((basis.translate_x, [1.0, 0.0]), (basis.translate_y, [0.0, 1.0])):
        np.testing.assert_allclose(basis.desired_velocities(A), np.tile(want, (f.n, 1)),
                                   atol=1e-12)
        # like the paper's A_v: a vehicle only uses its own edges
        assert np.all(A[f.incidence == 0] == 0)


@pytest.mark.parametrize("config", TEAMS)
def test_rotation_disagreements_reproduce_the_spin_about_the_centroid(config: str) -> None:
    f = load_team(config).formation
    basis = motion_basis(f)
    spin = np.column_stack((-f.positions[:, 1], f.positions[:, 0]))  # omega x r, 1 rad/s
    np.testing.assert_allclose(basis.desired_velocities(basis.rotate), spin, atol=1e-12)
    assert np.all(basis.rotate[f.incidence == 0] == 0)


def test_square_rotation_uses_the_sides_with_equal_disagreements() -> None:
    """The paper's spin: each vehicle combines its two sides; the diagonal is radial."""
    f = load_team(SQUARE).formation
    R = motion_basis(f).rotate
    diagonals = [1, 4]
    np.testing.assert_allclose(R[:, diagonals], 0, atol=1e-12)
    sides = np.abs(R[np.abs(R) > 1e-9])
    np.testing.assert_allclose(sides, 0.5)  # omega * side / 2 per rad/s


@pytest.mark.parametrize("config", TEAMS)
@pytest.mark.parametrize("vx, vy, omega", [(0.0, 0.0, 0.4), (0.5, -0.2, 0.3), (0.7, 0.1, 0.0)])
def test_proposition_1_centripetal_term(config: str, vx: float, vy: float, omega: float) -> None:
    """A_a zhat* equals the acceleration of the rigid motion: omega x v*."""
    f = load_team(config).formation
    basis = motion_basis(f)
    A_v = basis.velocity_matrix(vx, vy, omega, 1.0)
    z = f.relative(f.positions)
    zhat = z / np.linalg.norm(z, axis=1, keepdims=True)
    a = centripetal_matrix(A_v, f.incidence, f.distances) @ zhat
    v = basis.desired_velocities(A_v)
    np.testing.assert_allclose(a, omega * np.column_stack((-v[:, 1], v[:, 0])), atol=1e-12)
