"""Ground-control station for a rigid team of rotorcraft carrying one payload."""

from pathlib import Path

from vehicles.jit_cache import refresh_numba_cache

refresh_numba_cache(Path(__file__).parent, [Path(__file__).parent])
