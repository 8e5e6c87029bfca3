"""Ready-made teams: default config files, world plus autopilots, a blocking take-off.

For scripts, benchmarks and tests that want a flying team in a few lines; the
sim host builds its team the same way from its own configs.
"""

from __future__ import annotations

import numpy as np

from gcs.common import shipped_config
from gcs.wire import SimMode
from sim._config import WorldConfig
from sim._layout import Layout
from sim._world import World
from vehicles import BEBOP2, Airframe, Autopilot, AutopilotConfig

__all__ = [
    "DEFAULT_AIRFRAME",
    "DEFAULT_AUTOPILOT_CONFIG",
    "DEFAULT_WORLD_CONFIG",
    "build_team",
    "take_off",
]

DEFAULT_AIRFRAME = BEBOP2
"""The Bebop 2 airframe file."""
DEFAULT_WORLD_CONFIG = shipped_config("sim/default.yaml")
"""The default world (ropes, ground, wind, sensors) file."""
DEFAULT_AUTOPILOT_CONFIG = shipped_config("sim/autopilot.yaml")
"""The default onboard autopilot file."""


def build_team(layout: Layout, *, payload_mass: float, rng: np.random.Generator,
               airframe: Airframe, world_config: WorldConfig,
               autopilot_config: AutopilotConfig,
               autopilot_airframe: Airframe | None = None) -> tuple[World, Autopilot]:
    """A world with the team placed as ``layout`` and one disarmed autopilot per vehicle.

    ``autopilot_airframe`` is the autopilots' model of the vehicle (default: the
    true ``airframe``); give a different one to fly with model errors.
    """
    world = World(airframe=airframe, config=world_config, p0_ned=layout.p0_ned,
                  rope_length=layout.rope_length, payload_mass=payload_mass,
                  payload_p0_ned=layout.payload_p0_ned, rng=rng)
    autopilot = Autopilot(autopilot_airframe or airframe, autopilot_config, world.n_vehicles)
    return world, autopilot


def take_off(world: World, autopilot: Autopilot, altitude: float, *,
             timeout: float = 30.0) -> None:
    """Arm every vehicle, take off to ``altitude`` m and block until all HOLD there.

    Raises RuntimeError when a command is denied or the climb takes longer
    than ``timeout`` s of simulated time.
    """
    step = 1.0 / 32.0
    world.run(autopilot, step)  # first pose samples, so the autopilots can arm
    for i in range(world.n_vehicles):
        for result in (autopilot.arm(i), autopilot.takeoff(i, altitude)):
            if not result.accepted:
                raise RuntimeError(f"vehicle {i}: take-off {result.text}")
    waited = 0.0
    while not all(m == SimMode.HOLD for m in autopilot.modes):
        if waited >= timeout:
            modes = ", ".join(m.name for m in autopilot.modes)
            raise RuntimeError(f"take-off to {altitude} m not done after {timeout} s ({modes})")
        world.run(autopilot, step)
        waited += step
