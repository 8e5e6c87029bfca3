"""Physics of the team: quadrotors, ropes, payload, ground, sensors."""

from pathlib import Path

import vehicles
from sim.backend import PhysicsBackend
from sim.config import WorldConfig, load_world_config
from sim.layout import Layout, paper_square, ring_layout
from sim.scenario import build_team, take_off
from sim.world import World
from vehicles.jit_cache import refresh_numba_cache

__all__ = [
    "Layout",
    "PhysicsBackend",
    "World",
    "WorldConfig",
    "build_team",
    "load_world_config",
    "paper_square",
    "ring_layout",
    "take_off",
]

# The sim kernels inline the autopilot's, so both packages' sources key the cache.
refresh_numba_cache(Path(__file__).parent, [Path(__file__).parent, Path(vehicles.__file__).parent])
