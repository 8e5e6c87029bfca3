"""The formation's graph against the paper: the square's incidence (eq. B), rigidity,
positions realised from distances."""

from __future__ import annotations

import numpy as np

from gcs.config import load_team
from gcs.formation import build_formation
from gcs.formation._graph import is_infinitesimally_rigid
from tests.support.paths import SQUARE

# Eq. (B) of the paper, rows = vehicles 1..4, columns = z1..z6.
PAPER_B = np.array([
    [1, 0, 0, 1, 1, 0],
    [-1, 1, 0, 0, 0, 1],
    [0, 0, 1, 0, -1, -1],
    [0, -1, -1, -1, 0, 0],
])


def test_square_incidence_is_eq_B() -> None:
    f = load_team(SQUARE).formation
    np.testing.assert_array_equal(f.incidence, PAPER_B)
    np.testing.assert_allclose(f.distances, [1, np.sqrt(2), 1, 1, np.sqrt(2), 1])


def test_rigidity() -> None:
    square = np.array([[0.5, 0.5], [-0.5, 0.5], [-0.5, -0.5], [0.5, -0.5]])
    ring = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    assert not is_infinitesimally_rigid(square, ring)  # a square without diagonals shears
    assert is_infinitesimally_rigid(square, np.vstack([ring, [[0, 2]]]))
    # collinear triangle: all distances kept to first order by a perpendicular motion
    line = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    assert not is_infinitesimally_rigid(line, np.array([[0, 1], [1, 2], [0, 2]]))


def test_positions_realised_from_distances() -> None:
    f = build_formation([1, 2, 3, 4], [(1, 2), (2, 3), (3, 4), (4, 1), (1, 3)],
                        distances=[1.0, 1.0, 1.0, 1.0, np.sqrt(2)])
    z = f.relative(f.positions)
    np.testing.assert_allclose(np.linalg.norm(z, axis=1), [1, 1, 1, 1, np.sqrt(2)], atol=1e-6)
    np.testing.assert_allclose(f.positions.mean(axis=0), 0, atol=1e-9)
