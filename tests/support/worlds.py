"""The simulator's world with one vehicle: hanging on a rope too long to pull
(:func:`solo`, with its autopilot), or high up with nothing to touch (:func:`aloft`)."""

from __future__ import annotations

import numpy as np

from sim import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    Layout,
    build_team,
    load_world_config,
)
from sim._world import World
from vehicles import Airframe, Autopilot, AutopilotConfig, load_airframe, load_autopilot_config

SOLO = Layout(np.zeros((1, 3)), np.array([20.0]), np.array([0.0, 3.0, 0.0]))
"""One vehicle whose rope is too long to ever pull."""


def solo(config: AutopilotConfig | None = None) -> tuple[World, Autopilot]:
    """:data:`SOLO`'s world and the vehicle's autopilot (``config``, default the shipped)."""
    return build_team(SOLO, payload_mass=0.4, rng=np.random.default_rng(8),
                      airframe=load_airframe(DEFAULT_AIRFRAME),
                      world_config=load_world_config(DEFAULT_WORLD_CONFIG),
                      autopilot_config=config or load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))


def aloft(airframe: Airframe) -> World:
    """One vehicle 500 m up on a rope it never reaches: no ground, no rope, no wind."""
    return World(airframe=airframe, config=load_world_config(DEFAULT_WORLD_CONFIG),
                 p0_ned=np.array([[0.0, 0.0, -500.0]]), rope_length=np.array([1000.0]),
                 payload_mass=0.4, payload_p0_ned=np.array([0.0, 0.0, -499.0]),
                 rng=np.random.default_rng(0))
