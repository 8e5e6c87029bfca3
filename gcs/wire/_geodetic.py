"""Geodetic positions and local NED frames on the WGS-84 ellipsoid.

Why: a GPS autopilot reports where it is as latitude, longitude and altitude
(GLOBAL_POSITION_INT, GPS_GLOBAL_ORIGIN, HOME_POSITION) and flies in a local
NED frame about its own origin. The GCS ties vehicles with different origins
into one team frame, and the simulator turns its flat world into global
positions, with the same two functions, so both sides agree to the millimetre.

The local frame is the tangent plane at the origin: north and east along the
ellipsoid's surface there, down along its normal (exact, no flat-earth
approximation: a point 1 km away lies 78 mm below the plane). Altitudes are
heights above the ellipsoid; nothing here models a geoid, so where MAVLink says
AMSL the simulator sends the same number. Angles in degrees, lengths in
metres; every function takes arrays of any leading shape (``(..., 3)``).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["WGS84_A", "WGS84_F", "Geodetic", "ecef_to_geodetic", "geodetic_to_ecef",
           "geodetic_to_ned", "ned_to_geodetic"]

WGS84_A = 6378137.0
"""WGS-84 semi-major axis, m."""
WGS84_F = 1.0 / 298.257223563
"""WGS-84 flattening."""
_E2 = WGS84_F * (2.0 - WGS84_F)
"""First eccentricity squared."""
_ITERATIONS = 4
"""Latitude iterations of :func:`ecef_to_geodetic`: from the start below, the error falls by
about e^2 (1/150) per iteration, so four leave under 1e-12 rad anywhere near the surface."""


class Geodetic(NamedTuple):
    """One geodetic position: latitude and longitude in degrees, height above WGS-84 in m."""

    lat_deg: float
    lon_deg: float
    alt_m: float

    def check(self, what: str = "position") -> Geodetic:
        """Itself, or ValueError naming ``what`` when it is not a place on Earth."""
        if not all(math.isfinite(v) for v in self):
            raise ValueError(f"{what}: latitude, longitude and altitude must be finite, "
                             f"got {tuple(self)}")
        if not -90.0 <= self.lat_deg <= 90.0 or not -180.0 <= self.lon_deg <= 180.0:
            raise ValueError(f"{what}: latitude must be within +-90 and longitude within "
                             f"+-180 degrees, got {self.lat_deg}, {self.lon_deg}")
        return self


def geodetic_to_ecef(lla: ArrayLike) -> np.ndarray:
    """Earth-centred, Earth-fixed x, y, z (m) of latitude, longitude (deg), height (m)."""
    g = np.asarray(lla, dtype=np.float64)
    lat, lon, h = np.radians(g[..., 0]), np.radians(g[..., 1]), g[..., 2]
    s, c = np.sin(lat), np.cos(lat)
    n = WGS84_A / np.sqrt(1.0 - _E2 * s * s)
    return np.stack([(n + h) * c * np.cos(lon), (n + h) * c * np.sin(lon),
                     (n * (1.0 - _E2) + h) * s], axis=-1)


def ecef_to_geodetic(xyz: ArrayLike) -> np.ndarray:
    """Latitude, longitude (deg), height (m) of Earth-centred, Earth-fixed x, y, z (m)."""
    r = np.asarray(xyz, dtype=np.float64)
    x, y, z = r[..., 0], r[..., 1], r[..., 2]
    p = np.hypot(x, y)
    lat = np.arctan2(z, p * (1.0 - _E2))
    for _ in range(_ITERATIONS):
        s = np.sin(lat)
        n = WGS84_A / np.sqrt(1.0 - _E2 * s * s)
        lat = np.arctan2(z + _E2 * n * s, p)
    s, c = np.sin(lat), np.cos(lat)
    h = p * c + z * s - WGS84_A * np.sqrt(1.0 - _E2 * s * s)  # sound at the poles too
    return np.stack([np.degrees(lat), np.degrees(np.arctan2(y, x)), h], axis=-1)


def _ned_axes(origin: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The origin's ECEF position and the rows north, east, down as a (3, 3) matrix."""
    o = np.asarray(origin, dtype=np.float64)
    if o.shape != (3,):
        raise ValueError(f"origin must be (latitude, longitude, altitude), got shape {o.shape}")
    return _axes_at(float(o[0]), float(o[1]), float(o[2]))


@functools.lru_cache(maxsize=64)
def _axes_at(lat_deg: float, lon_deg: float, alt_m: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_ned_axes` of one origin, kept: a vehicle converts against the same few
    origins many times a second (read-only arrays, shared by every caller)."""
    o = np.array([lat_deg, lon_deg, alt_m])
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    sl, cl, so, co = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    axes = np.array([[-sl * co, -sl * so, cl],
                     [-so, co, 0.0],
                     [-cl * co, -cl * so, -sl]])
    centre = geodetic_to_ecef(o)
    axes.flags.writeable = centre.flags.writeable = False
    return centre, axes


def geodetic_to_ned(lla: ArrayLike, origin: ArrayLike) -> np.ndarray:
    """NED position (m) in the tangent plane at ``origin`` of geodetic positions ``lla``."""
    centre, axes = _ned_axes(origin)
    return (geodetic_to_ecef(lla) - centre) @ axes.T


def ned_to_geodetic(p_ned: ArrayLike, origin: ArrayLike) -> np.ndarray:
    """Geodetic positions (deg, deg, m) of NED positions (m) in the tangent plane at
    ``origin``; the inverse of :func:`geodetic_to_ned`."""
    centre, axes = _ned_axes(origin)
    return ecef_to_geodetic(np.asarray(p_ned, dtype=np.float64) @ axes + centre)
