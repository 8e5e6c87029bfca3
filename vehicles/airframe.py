"""Airframe parameters of one rotorcraft, loaded from configs/airframes/*.yaml.

Bebop 2 defaults: mass from the paper (about 0.4 kg); thrust from the paper's
measurement (1.6 N per motor at 85 % of capacity, at about 160 Hz rotor speed)
and the seed's reference (about 1.87 N per motor at full throttle); inertia and
arm geometry are typical published Bebop 2 figures; rotor time constant about
20 ms (the seed's actuator model).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gcs.typed_config import field, from_mapping, load_yaml

__all__ = ["Airframe", "load_airframe"]


@dataclass(frozen=True)
class Airframe:
    """Physical parameters of one quadrotor (X configuration, FRD body frame)."""

    name: str = field(doc="airframe name", default="bebop2")
    mass: float = field(doc="take-off mass, kg", default=0.4, gt=0.0)
    inertia: tuple[float, float, float] = field(
        doc="principal moments of inertia about body x, y, z, kg m^2",
        default=(0.00223, 0.00299, 0.00480), gt=0.0)
    arm_x: float = field(doc="rotor offset along body x from the centre of mass, m",
                         default=0.0826, gt=0.0)
    arm_y: float = field(doc="rotor offset along body y from the centre of mass, m",
                         default=0.1100, gt=0.0)
    thrust_coefficient: float = field(doc="rotor thrust per squared rotor speed, N/(rad/s)^2",
                                      default=1.584e-6, gt=0.0)
    torque_ratio: float = field(doc="rotor drag torque per unit thrust, m", default=0.016, gt=0.0)
    rotor_speed_max: float = field(doc="largest rotor speed, rad/s", default=1086.0, gt=0.0)
    rotor_time_constant: float = field(doc="first-order rotor speed time constant, s",
                                       default=0.02, gt=0.0)
    thrust_reference: float = field(
        doc="total thrust at 85 % of capacity used by the worst-case analysis, N",
        default=6.4, gt=0.0)
    drag_coefficient: float = field(doc="linear aerodynamic drag per unit airspeed, N s/m",
                                    default=0.05, ge=0.0)

    @property
    def thrust_max(self) -> float:
        """Total thrust with all rotors at full speed, N."""
        return 4.0 * self.thrust_coefficient * self.rotor_speed_max**2


def load_airframe(path: str | Path) -> Airframe:
    """Load and validate an airframe file."""
    return from_mapping(Airframe, load_yaml(path) or {}, str(path))
