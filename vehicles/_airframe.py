"""Airframe parameters of one rotorcraft, loaded from configs/airframes/*.yaml.

Every field is required and has no default: an airframe is a physical vehicle,
and a file that forgets its mass must be refused (one line naming the file and
the field), not flown or analysed with another vehicle's figures. So is an
airframe no vehicle can be: rotors that cannot lift its weight, a thrust
reference beyond them, impossible moments of inertia. The Bebop 2
the paper flies is configs/airframes/bebop2.yaml (:func:`bebop2` loads it);
the sources of its figures are noted there.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gcs.common import (
    STANDARD_GRAVITY,
    ConfigError,
    field,
    from_mapping,
    load_yaml,
    shipped_config,
)

__all__ = ["BEBOP2", "Airframe", "bebop2", "check_airframe", "load_airframe"]

"""m/s^2: the weight an airframe must lift to hover (a team's own gravity is checked by the
GCS's analysis)."""

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


def check_airframe(frame: Airframe, source: str, where: str = "") -> None:
    """Refuse an airframe no physical vehicle can be (ConfigError naming ``source`` and the
    field under ``where``): rotors that cannot lift its weight, a thrust reference beyond
    them, principal moments of inertia that break the triangle inequality.

    A check of what a file says, not of the class: a simulated autopilot may believe
    its rotors weaker than they are (``dataclasses.replace``).
    """

    def at(name: str) -> str:
        return f"{where}.{name}" if where else name

    weight = frame.mass * STANDARD_GRAVITY
    if not frame.thrust_max > weight:
        raise ConfigError(source, at("thrust_coefficient"),
                          f"4 x thrust_coefficient x rotor_speed_max^2 = "
                          f"{frame.thrust_max:.3g} N at full rotor speed cannot lift the "
                          f"weight {weight:.3g} N (mass {frame.mass:g} kg): the airframe "
                          f"cannot hover")
    if frame.thrust_reference > frame.thrust_max:
        raise ConfigError(source, at("thrust_reference"),
                          f"{frame.thrust_reference:g} N exceeds the full-speed thrust "
                          f"{frame.thrust_max:.3g} N (4 x thrust_coefficient x "
                          f"rotor_speed_max^2)")
    for k, name in enumerate("xyz"):
        others = sum(frame.inertia) - frame.inertia[k]
        if frame.inertia[k] > others * (1.0 + 1e-9):
            raise ConfigError(source, at("inertia"),
                              f"I{name} {frame.inertia[k]:g} kg m^2 exceeds the sum of the "
                              f"other two {others:g} kg m^2: the principal moments of a rigid "
                              f"body satisfy the triangle inequality")


def load_airframe(path: str | Path) -> Airframe:
    """Load and validate an airframe file (:func:`check_airframe` included)."""
    frame = from_mapping(Airframe, load_yaml(path) or {}, str(path))
    check_airframe(frame, str(path))
    return frame


def bebop2() -> Airframe:
    """The Bebop 2 from its file: code that needs a concrete vehicle names it, no defaults."""
    return load_airframe(BEBOP2)
