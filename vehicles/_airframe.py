"""Airframe parameters of one rotorcraft, loaded from configs/airframes/*.yaml.

Every field is required and has no default: an airframe is a physical vehicle,
and a file that forgets its mass must be refused (one line naming the file and
the field), not flown or analysed with another vehicle's figures. The Bebop 2
the paper flies is configs/airframes/bebop2.yaml (:func:`bebop2` loads it);
the sources of its figures are noted there.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gcs.common import field, from_mapping, load_yaml, shipped_config

__all__ = ["BEBOP2", "Airframe", "bebop2", "load_airframe"]

BEBOP2 = shipped_config("airframes/bebop2.yaml")
"""The paper's vehicle, the Parrot Bebop 2."""


@dataclass(frozen=True)
class Airframe:
    """Physical parameters of one quadrotor (X configuration, FRD body frame)."""

    name: str = field(doc="airframe name")
    mass: float = field(doc="take-off mass, kg", gt=0.0)
    inertia: tuple[float, float, float] = field(
        doc="principal moments of inertia about body x, y, z, kg m^2", gt=0.0)
    arm_x: float = field(doc="rotor offset along body x from the centre of mass, m", gt=0.0)
    arm_y: float = field(doc="rotor offset along body y from the centre of mass, m", gt=0.0)
    thrust_coefficient: float = field(doc="rotor thrust per squared rotor speed, N/(rad/s)^2",
                                      gt=0.0)
    torque_ratio: float = field(doc="rotor drag torque per unit thrust, m", gt=0.0)
    rotor_speed_max: float = field(doc="largest rotor speed, rad/s", gt=0.0)
    rotor_time_constant: float = field(doc="first-order rotor speed time constant, s",
                                       gt=0.0)
    thrust_reference: float = field(
        doc="total thrust at 85 % of capacity used by the worst-case analysis, N", gt=0.0)
    drag_coefficient: float = field(doc="linear aerodynamic drag per unit airspeed, N s/m",
                                    ge=0.0)

    @property
    def thrust_max(self) -> float:
        """Total thrust with all rotors at full speed, N."""
        return 4.0 * self.thrust_coefficient * self.rotor_speed_max**2


def load_airframe(path: str | Path) -> Airframe:
    """Load and validate an airframe file."""
    return from_mapping(Airframe, load_yaml(path) or {}, str(path))


def bebop2() -> Airframe:
    """The Bebop 2 from its file: code that needs a concrete vehicle names it, no defaults."""
    return load_airframe(BEBOP2)
