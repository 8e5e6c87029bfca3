"""What a simulation host (the zenoh/MAVLink sim process) needs from a physics backend.

:class:`sim.World` is the rigid-body implementation. Another backend
(for example one that tracks commanded accelerations perfectly, to test the
command path without physics) only has to provide these members.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from vehicles import Autopilot, Measurements

__all__ = ["PhysicsBackend"]


class PhysicsBackend(Protocol):
    """Steppable world whose vehicles are flown by an :class:`~vehicles.Autopilot`."""

    @property
    def n_vehicles(self) -> int:
        """Number of vehicles."""
        ...

    @property
    def t(self) -> float:
        """Simulated time, s."""
        ...

    def run(self, autopilot: Autopilot, duration: float) -> None:
        """Advance ``duration`` s in lockstep with the autopilot (blocks until done)."""
        ...

    def measurements(self) -> Measurements:
        """Latest sensor samples (what telemetry like HIGHRES_IMU reports)."""
        ...

    @property
    def p_ned(self) -> np.ndarray:
        """(N, 3) true vehicle positions, m."""
        ...

    @property
    def q_wxyz(self) -> np.ndarray:
        """(N, 4) true vehicle attitudes."""
        ...

    @property
    def payload_p_ned(self) -> np.ndarray:
        """(3,) true payload position, m."""
        ...

    @property
    def rope_tension(self) -> np.ndarray:
        """(N,) rope tensions, N."""
        ...
