"""World configuration: integration rate, ropes, payload drag, ground, wind, sensors, and
where on Earth the world lies.

Loaded from configs/sim/default.yaml. What differs per run (airframe, start
positions, rope lengths, payload mass) is passed to :class:`sim.World`
explicitly instead.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gcs.common import STANDARD_GRAVITY, field, from_mapping, load_yaml
from gcs.wire import Geodetic
from vehicles.endpoint import DEFAULT_REFERENCE

__all__ = [
    "GroundConfig",
    "HomeConfig",
    "RopeConfig",
    "SensorConfig",
    "WindConfig",
    "WorldConfig",
    "load_world_config",
]


@dataclass(frozen=True)
class RopeConfig:
    """Massless rope: a spring-damper that acts only in extension and never pushes."""

    stiffness: float = field(doc="tension per metre of stretch, N/m", default=5000.0, gt=0.0)
    damping: float = field(doc="tension per stretch rate while taut, N s/m", default=30.0,
                           ge=0.0)


@dataclass(frozen=True)
class GroundConfig:
    """Flat ground: penalty contact at each vehicle's four rotor points and at the payload."""

    z_ned: float = field(doc="ground height as NED z, m", default=0.0)
    stiffness: float = field(doc="normal force per metre of penetration per contact point, N/m",
                             default=2000.0, gt=0.0)
    damping: float = field(doc="normal force per penetration rate per contact point, N s/m",
                           default=20.0, ge=0.0)
    friction_coefficient: float = field(doc="Coulomb friction bound, tangential / normal force",
                                        default=0.8, ge=0.0)
    friction_damping: float = field(
        doc="tangential force per sliding speed below the Coulomb bound, N s/m", default=20.0,
        ge=0.0)


@dataclass(frozen=True)
class WindConfig:
    """Uniform wind: a constant part plus a first-order (Ornstein-Uhlenbeck) gust per axis."""

    mean_ned: tuple[float, float, float] = field(doc="constant wind velocity, NED, m/s",
                                                 default=(0.0, 0.0, 0.0))
    gust_std: float = field(doc="standard deviation of the gust velocity per axis, m/s",
                            default=0.0, ge=0.0)
    gust_time_constant: float = field(doc="correlation time of the gust, s", default=2.0, gt=0.0)


@dataclass(frozen=True)
class SensorConfig:
    """Sample rates and white-noise levels of the simulated sensors."""

    imu_rate_hz: float = field(doc="accelerometer and gyro sample rate, Hz", default=512.0,
                               gt=0.0)
    accel_noise_std: float = field(doc="accelerometer noise per axis, m/s^2", default=0.3,
                                   ge=0.0)
    gyro_noise_std: float = field(doc="gyro noise per axis, rad/s", default=0.005, ge=0.0)
    pose_rate_hz: float = field(doc="motion-capture (position, velocity, attitude) rate, Hz",
                                default=128.0, gt=0.0)
    position_noise_std: float = field(doc="position noise per axis, m", default=0.002, ge=0.0)
    velocity_noise_std: float = field(doc="velocity noise per axis, m/s", default=0.01, ge=0.0)
    attitude_noise_std: float = field(doc="attitude noise per axis (small rotation), rad",
                                      default=0.003, ge=0.0)


@dataclass(frozen=True)
class HomeConfig:
    """Where the world's NED origin (the payload's start) lies on Earth: the reference every
    vehicle's GPS, global position, home and origin are given from."""

    latitude_deg: float = field(doc="latitude, degrees north", default=DEFAULT_REFERENCE.lat_deg,
                                ge=-90.0, le=90.0)
    longitude_deg: float = field(doc="longitude, degrees east",
                                 default=DEFAULT_REFERENCE.lon_deg, ge=-180.0, le=180.0)
    altitude_m: float = field(doc="height above the WGS-84 ellipsoid (sent as AMSL: no "
                              "geoid), m", default=DEFAULT_REFERENCE.alt_m, ge=-1000.0,
                              le=20000.0)

    @property
    def geodetic(self) -> Geodetic:
        """As a :class:`gcs.wire.Geodetic`."""
        return Geodetic(self.latitude_deg, self.longitude_deg, self.altitude_m)


@dataclass(frozen=True)
class WorldConfig:
    """Everything about the simulated world except the team's own arrays."""

    physics_rate_hz: float = field(
        doc="integration rate, Hz; a whole multiple of the autopilot and sensor rates",
        default=2048.0, gt=0.0)
    gravity: float = field(doc="gravitational acceleration, m/s^2 (standard gravity, as the "
                           "team's analysis)", default=STANDARD_GRAVITY, gt=0.0)
    payload_drag_coefficient: float = field(doc="linear payload drag per airspeed, N s/m",
                                            default=0.02, ge=0.0)
    rope: RopeConfig = field(doc="rope model", default_factory=RopeConfig)
    ground: GroundConfig = field(doc="ground contact model", default_factory=GroundConfig)
    wind: WindConfig = field(doc="wind model", default_factory=WindConfig)
    sensors: SensorConfig = field(doc="sensor rates and noise", default_factory=SensorConfig)
    home: HomeConfig = field(doc="geodetic position of the world's NED origin",
                             default_factory=HomeConfig)

    def __post_init__(self) -> None:
        for name, rate in (("sensors.imu_rate_hz", self.sensors.imu_rate_hz),
                           ("sensors.pose_rate_hz", self.sensors.pose_rate_hz)):
            if not _divides(rate, self.physics_rate_hz):
                raise ValueError(f"{name} ({rate:g} Hz) must divide physics_rate_hz "
                                 f"({self.physics_rate_hz:g} Hz) into whole steps")


def _divides(rate: float, physics_rate: float) -> bool:
    ratio = physics_rate / rate
    return ratio >= 1.0 and abs(ratio - round(ratio)) < 1e-9


def load_world_config(path: str | Path) -> WorldConfig:
    """Load and validate a world configuration file."""
    return from_mapping(WorldConfig, load_yaml(path) or {}, str(path))
