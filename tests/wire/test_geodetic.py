"""Geodetic positions and local NED frames (``gcs.wire._geodetic``): exact to the millimetre,
as the simulator's global positions and the GCS's team frame both need; a vehicle's local
origin from its fixes; medians and means of positions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gcs.wire import (
    Geodetic,
    ecef_to_geodetic,
    geodetic_mean,
    geodetic_median,
    geodetic_to_ecef,
    geodetic_to_ned,
    local_origin,
    ned_to_geodetic,
)
from gcs.wire._geodetic import WGS84_A, WGS84_F

ORIGIN = Geodetic(52.0, 4.37, 0.0)
FAR_NORTH = Geodetic(69.65, 18.95, 20.0)
"""A field at 70 degrees north, where a sphere of the equator's radius is 0.2-0.3 % off."""
E2 = WGS84_F * (2.0 - WGS84_F)


def meridian_radius(lat_deg: float) -> float:
    """Radius of curvature along the meridian, m (the textbook formula)."""
    s = math.sin(math.radians(lat_deg))
    return WGS84_A * (1.0 - E2) / (1.0 - E2 * s * s) ** 1.5


def normal_radius(lat_deg: float) -> float:
    """Radius of curvature in the prime vertical, m."""
    s = math.sin(math.radians(lat_deg))
    return WGS84_A / math.sqrt(1.0 - E2 * s * s)


def test_round_trip_is_exact_to_well_below_a_millimetre_over_kilometres() -> None:
    rng = np.random.default_rng(3)
    points = rng.uniform(-5000.0, 5000.0, (500, 3)) * [1.0, 1.0, 0.1]
    for origin in (ORIGIN, Geodetic(-33.9, 151.2, 40.0), Geodetic(0.0, 179.999, -20.0),
                   Geodetic(89.5, -120.0, 2000.0)):
        back = geodetic_to_ned(ned_to_geodetic(points, origin), origin)
        assert np.abs(back - points).max() < 1e-6  # 1 micrometre


def test_small_offsets_match_the_radii_of_curvature() -> None:
    north = ned_to_geodetic((10.0, 0.0, 0.0), ORIGIN)
    east = ned_to_geodetic((0.0, 10.0, 0.0), ORIGIN)
    assert math.radians(north[0] - ORIGIN.lat_deg) * meridian_radius(52.0) == pytest.approx(
        10.0, abs=1e-6)
    lon_radius = normal_radius(52.0) * math.cos(math.radians(52.0))
    assert math.radians(east[1] - ORIGIN.lon_deg) * lon_radius == pytest.approx(10.0, abs=1e-6)
    up = ned_to_geodetic((0.0, 0.0, -3.0), ORIGIN)
    assert up == pytest.approx((52.0, 4.37, 3.0), abs=1e-9)


def test_the_tangent_plane_leaves_the_surface_as_the_earth_curves() -> None:
    """1 km north along the plane is 1 km / (2 M) above the ellipsoid: 78 mm, no flat earth."""
    drop = 1000.0**2 / (2.0 * meridian_radius(52.0))
    assert ned_to_geodetic((1000.0, 0.0, 0.0), ORIGIN)[2] == pytest.approx(drop, abs=1e-4)
    assert drop == pytest.approx(0.0784, abs=1e-4)


def test_ecef_of_landmarks_and_array_shapes() -> None:
    b = WGS84_A * (1.0 - WGS84_F)
    ecef = geodetic_to_ecef([[0.0, 0.0, 0.0], [90.0, 0.0, 0.0], [0.0, 90.0, 10.0]])
    assert ecef == pytest.approx(np.array([[WGS84_A, 0, 0], [0, 0, b], [0, WGS84_A + 10, 0]]),
                                 abs=1e-6)
    assert ecef_to_geodetic(ecef) == pytest.approx(
        np.array([[0, 0, 0], [90, 0, 0], [0, 90, 10]]), abs=1e-9)
    grid = np.zeros((2, 5, 3))
    assert ned_to_geodetic(grid, ORIGIN).shape == (2, 5, 3)
    assert geodetic_to_ned(ned_to_geodetic(grid, ORIGIN), ORIGIN) == pytest.approx(grid,
                                                                                abs=1e-8)
    with pytest.raises(ValueError, match="origin must be"):
        ned_to_geodetic((0.0, 0.0, 0.0), (52.0, 4.37))


def test_a_geodetic_position_is_checked_for_being_on_earth() -> None:
    assert ORIGIN.check() is ORIGIN
    with pytest.raises(ValueError, match="home: latitude must be within"):
        Geodetic(95.0, 0.0, 0.0).check("home")
    with pytest.raises(ValueError, match="must be finite"):
        Geodetic(52.0, math.nan, 0.0).check()


def test_a_local_origin_is_exact_kilometres_out_and_at_high_latitude() -> None:
    origin = np.array(FAR_NORTH)
    rng = np.random.default_rng(5)
    p = rng.uniform(-7000.0, 7000.0, (40, 3)) * [1.0, 1.0, 0.01]
    for k in range(len(p)):  # each pair on its own: the origin to a micrometre
        found = local_origin(ned_to_geodetic(p[k], origin)[None], p[k][None])
        assert np.abs(geodetic_to_ned(found, origin)).max() < 1e-6, p[k]
    fixes = ned_to_geodetic(p, origin)
    fixes[3] += (1e-3, 0.0, 50.0)  # a glitch, 111 m north and 50 m up, moves nothing
    assert np.abs(geodetic_to_ned(local_origin(fixes, p), origin)).max() < 1e-6


def test_medians_and_means_hold_across_the_antimeridian() -> None:
    points = [(-16.0, 179.9999, 10.0), (-16.0002, -179.9999, 12.0), (-16.0001, 179.9998, 11.0)]
    assert geodetic_median(points) == pytest.approx([-16.0001, 179.9999, 11.0], abs=1e-9)
    assert geodetic_mean(points[:2]) == pytest.approx([-16.0001, 180.0, 11.0], abs=1e-9) \
        or geodetic_mean(points[:2]) == pytest.approx([-16.0001, -180.0, 11.0], abs=1e-9)
    assert geodetic_mean([(0.0, 10.0, 0.0), (2.0, 20.0, 4.0)]).tolist() == [1.0, 15.0, 2.0]
