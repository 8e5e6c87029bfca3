"""Onboard autopilot of a simulated rotorcraft: INDI control, modes, MAVLink endpoint."""

from pathlib import Path

from vehicles.jit_cache import refresh_numba_cache

refresh_numba_cache(Path(__file__).parent, [Path(__file__).parent])
