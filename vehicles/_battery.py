"""Battery of a simulated vehicle: charge drawn by the rotors, voltage sag, remaining charge.

Why: SYS_STATUS should behave like a real flight pack (voltage drops when the
rotors pull harder and as the charge runs down), so the GCS's battery display
and warnings see realistic numbers.

Model: the rotors' electrical power comes from momentum theory,
``P = sum(T_k^1.5) / sqrt(2 rho A) / efficiency``, plus a constant avionics
current. The pack is an open-circuit voltage that follows the state of charge
(a typical LiPo cell curve) behind an internal resistance, so the current
solves ``P = I (V_oc - I R)``. Defaults: Parrot Bebop 2 (3S 2700 mAh pack,
15 cm propellers), which gives about 25 min of hover as Parrot advertises.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Iterable
from dataclasses import dataclass

__all__ = ["AIR_DENSITY", "Battery", "BatteryConfig", "BatteryReading"]

AIR_DENSITY = 1.225
"""Sea-level air density, kg/m^3."""

_SOC_POINTS = (0.0, 0.05, 0.1, 0.2, 0.5, 0.8, 1.0)
_CELL_VOLTS = (3.3, 3.5, 3.6, 3.7, 3.8, 3.95, 4.2)
"""Open-circuit voltage of one LiPo cell (V) against the state of charge."""


@dataclass(frozen=True)
class BatteryConfig:
    """Pack and propulsion figures (defaults: Parrot Bebop 2)."""

    cells: int = 3
    """Cells in series."""
    capacity_mah: float = 2700.0
    """Capacity, mAh."""
    internal_resistance_ohm: float = 0.06
    """Pack internal resistance, ohm."""
    avionics_current_a: float = 0.6
    """Current drawn with the rotors stopped, A."""
    rotor_disk_area_m2: float = 0.0177
    """Disk area of one propeller (15 cm diameter), m^2."""
    propulsion_efficiency: float = 0.3
    """Rotor figure of merit (about 0.55) times motor and ESC efficiency (about 0.55)."""

    def __post_init__(self) -> None:
        if self.cells < 1 or not all(v > 0 for v in (
                self.capacity_mah, self.internal_resistance_ohm, self.rotor_disk_area_m2,
                self.propulsion_efficiency)) or self.avionics_current_a < 0:
            raise ValueError(f"battery figures must be positive, got {self}")


@dataclass(frozen=True)
class BatteryReading:
    """What the battery monitor reports."""

    voltage_v: float
    """Terminal voltage under the present load, V."""
    current_a: float
    """Current drawn, A."""
    remaining: float
    """State of charge, 0..1."""


class Battery:
    """Charge and voltage of one pack; :meth:`draw` integrates the load over time."""

    def __init__(self, config: BatteryConfig | None = None, *, charge: float = 1.0) -> None:
        if not 0.0 <= charge <= 1.0:
            raise ValueError(f"charge must be within 0..1, got {charge}")
        self.config = config if config is not None else BatteryConfig()
        self._charge = charge
        self._current = self.config.avionics_current_a
        self._power_k = 1.0 / (math.sqrt(2.0 * AIR_DENSITY * self.config.rotor_disk_area_m2)
                               * self.config.propulsion_efficiency)

    def draw(self, rotor_thrust_n: Iterable[float], dt: float) -> None:
        """Spend ``dt`` s with each rotor producing ``rotor_thrust_n`` (N)."""
        cfg = self.config
        power = sum(max(0.0, float(f)) ** 1.5 for f in rotor_thrust_n) * self._power_k
        v_oc = self._open_circuit_voltage()
        r = cfg.internal_resistance_ohm
        # P = I (V_oc - I R): the smaller root; a pack that cannot deliver P gives V_oc / 2R.
        disc = max(0.0, v_oc * v_oc - 4.0 * r * power)
        self._current = (v_oc - math.sqrt(disc)) / (2.0 * r) + cfg.avionics_current_a
        used = self._current * max(0.0, dt) / 3600.0 / (cfg.capacity_mah / 1000.0)
        self._charge = max(0.0, self._charge - used)

    def reading(self) -> BatteryReading:
        """Voltage, current and remaining charge now."""
        v = self._open_circuit_voltage() - self._current * self.config.internal_resistance_ohm
        return BatteryReading(max(0.0, v), self._current, self._charge)

    def _open_circuit_voltage(self) -> float:
        """Cell curve interpolated linearly, times the cells."""
        k = min(max(bisect.bisect_right(_SOC_POINTS, self._charge), 1), len(_SOC_POINTS) - 1)
        s0, s1 = _SOC_POINTS[k - 1], _SOC_POINTS[k]
        v0, v1 = _CELL_VOLTS[k - 1], _CELL_VOLTS[k]
        return self.config.cells * (v0 + (v1 - v0) * (self._charge - s0) / (s1 - s0))
