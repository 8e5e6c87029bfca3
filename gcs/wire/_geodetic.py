"""Geodetic positions, local NED frames and the team frame, on the WGS-84 ellipsoid.

Why: a GPS autopilot reports where it is as latitude, longitude and altitude
(GLOBAL_POSITION_INT, GPS_GLOBAL_ORIGIN, HOME_POSITION) and flies in a local
NED frame about its own origin. The simulator turns its flat world into global
positions, the GCS ties vehicles with different origins into one team frame
live (``gcs.loop.TeamFrame``), and the log reader places the vehicles of a
recorded flight (``gcs.flightlog.FlightLog``), all with the functions here, so
they agree to the millimetre and a log shows a vehicle where the GCS had it.

The local frame is the tangent plane at the origin: north and east along the
ellipsoid's surface there, down along its normal (exact, no flat-earth
approximation: a point 1 km away lies 78 mm below the plane). Altitudes are
heights above the ellipsoid; nothing here models a geoid, so where MAVLink says
AMSL the simulator sends the same number. Angles in degrees, lengths in
metres; every function takes arrays of any leading shape (``(..., 3)``), and an
origin may be one position or one per point.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["WGS84_A", "WGS84_F", "Geodetic", "ecef_to_geodetic", "geodetic_mean",
           "geodetic_median", "geodetic_to_ecef", "geodetic_to_ned", "local_origin",
           "ned_to_geodetic"]

WGS84_A = 6378137.0
"""WGS-84 semi-major axis, m."""
WGS84_F = 1.0 / 298.257223563
"""WGS-84 flattening."""
_E2 = WGS84_F * (2.0 - WGS84_F)
"""First eccentricity squared."""
_ITERATIONS = 4
"""Latitude iterations of :func:`ecef_to_geodetic`: from the start below, the error falls by
about e^2 (1/150) per iteration, so four leave under 1e-12 rad anywhere near the surface."""
_ORIGIN_PASSES = 4
"""Passes of :func:`_frame_origins`: the first takes the fix's tangent plane for the origin's
(off by metres 5 km out); each next one divides the error by several hundred there, so four
leave under a micrometre anywhere within 10 km of the origin."""


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
    """The origin's ECEF position and the rows north, east, down as a (3, 3) matrix; for
    origins of shape (..., 3), one of each per origin."""
    o = np.asarray(origin, dtype=np.float64)
    if o.ndim == 0 or o.shape[-1] != 3:
        raise ValueError(f"origin must be (latitude, longitude, altitude), got shape {o.shape}")
    if o.ndim == 1:
        return _axes_at(float(o[0]), float(o[1]), float(o[2]))
    return geodetic_to_ecef(o), _axes(o[..., 0], o[..., 1])


@functools.lru_cache(maxsize=64)
def _axes_at(lat_deg: float, lon_deg: float, alt_m: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_ned_axes` of one origin, kept: a vehicle converts against the same few
    origins many times a second (read-only arrays, shared by every caller)."""
    centre = geodetic_to_ecef(np.array([lat_deg, lon_deg, alt_m]))
    axes = _axes(lat_deg, lon_deg)
    axes.flags.writeable = centre.flags.writeable = False
    return centre, axes


def _axes(lat_deg: ArrayLike, lon_deg: ArrayLike) -> np.ndarray:
    """Rows north, east, down (in ECEF) of the tangent planes at latitudes and longitudes
    (deg) of any shape S: (*S, 3, 3)."""
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    sl, cl, so, co = np.sin(lat), np.cos(lat), np.sin(lon), np.cos(lon)
    return np.stack([np.stack([-sl * co, -sl * so, cl], axis=-1),
                     np.stack([-so, co, np.zeros_like(so)], axis=-1),
                     np.stack([-cl * co, -cl * so, -sl], axis=-1)], axis=-2)


def _rotate(axes: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``axes @ v`` for vectors (..., 3): one matrix (3, 3) for all, or one per vector."""
    if axes.ndim == 2:
        return v @ axes.T
    return np.einsum("...ij,...j->...i", axes, v)


def geodetic_to_ned(lla: ArrayLike, origin: ArrayLike) -> np.ndarray:
    """NED position (m) in the tangent plane at ``origin`` of geodetic positions ``lla``."""
    centre, axes = _ned_axes(origin)
    return _rotate(axes, geodetic_to_ecef(lla) - centre)


def ned_to_geodetic(p_ned: ArrayLike, origin: ArrayLike) -> np.ndarray:
    """Geodetic positions (deg, deg, m) of NED positions (m) in the tangent plane at
    ``origin``; the inverse of :func:`geodetic_to_ned`."""
    centre, axes = _ned_axes(origin)
    p = np.asarray(p_ned, dtype=np.float64)
    return ecef_to_geodetic(_rotate(np.swapaxes(axes, -1, -2), p) + centre)


# -- the team frame -----------------------------------------------------------------------------

def _frame_origins(fixes: ArrayLike, p_local: ArrayLike) -> np.ndarray:
    """Per pair, the origin (deg, deg, m) of the local NED frame in which a vehicle at
    ``fixes`` (deg, deg, m) is at ``p_local`` (m): ``ned_to_geodetic(p_local, origin)`` is
    the fix. The frame's axes are the origin's, not yet known: solved by passes."""
    fix = geodetic_to_ecef(fixes)
    p = np.asarray(p_local, dtype=np.float64)
    origin = np.asarray(fixes, dtype=np.float64)
    for _ in range(_ORIGIN_PASSES):
        axes = _axes(origin[..., 0], origin[..., 1])
        origin = ecef_to_geodetic(fix - _rotate(np.swapaxes(axes, -1, -2), p))
    return origin


def local_origin(fixes: ArrayLike, p_local: ArrayLike) -> np.ndarray:
    """Where a vehicle's local NED frame has its origin (deg, deg, m), from its fixes
    (GLOBAL_POSITION_INT: K, 3) and its local positions at the same moments (K, 3, m).

    Why: an autopilot that does not report its origin still shows it, each fix less
    its local position; the median over the pairs (:func:`geodetic_median`), so one
    glitch moves nothing. The live team frame and the log reader both take a vehicle's
    origin from here, so a log places it where the GCS did.
    """
    return geodetic_median(_frame_origins(fixes, p_local))


def _unwrapped(lla: ArrayLike) -> np.ndarray:
    """Positions (K, 3) with longitudes within 180 degrees of the first (across the
    antimeridian, 179.9 and -179.9 are 0.2 degrees apart, not 359.8)."""
    g = np.array(lla, dtype=np.float64).reshape(-1, 3)
    turn = g[:, 1] - g[0, 1]
    g[turn > 180.0, 1] -= 360.0
    g[turn < -180.0, 1] += 360.0
    return g


def _wrapped(lla: np.ndarray) -> np.ndarray:
    """``lla`` (3,) with its longitude back within +-180 degrees."""
    if abs(lla[1]) > 180.0:
        lla[1] -= math.copysign(360.0, lla[1])
    return lla


def geodetic_median(lla: ArrayLike) -> np.ndarray:
    """The median latitude, longitude and height of positions (K, 3): one position that a
    few outliers do not move (a vehicle's origin from many estimates)."""
    return _wrapped(np.median(_unwrapped(lla), axis=0))


def geodetic_mean(lla: ArrayLike) -> np.ndarray:
    """The mean latitude, longitude and height of positions (K, 3): the team origin
    between the vehicles' own origins."""
    return _wrapped(np.mean(_unwrapped(lla), axis=0))
