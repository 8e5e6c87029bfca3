"""The pytest plugin ``formation_gcs``: a ``sim_team`` fixture for a user's own test suite.

Registered through the package's ``pytest11`` entry point, so installing
formation-gcs gives every test suite in that environment the fixture::

    def test_lift(sim_team):
        team = sim_team("bebop_square.yaml", seed=1)
        team.arm(); team.takeoff(); team.lift()
        assert team.metrics().payload_lift_m > 0.9

The fixture is a factory: each call starts a :class:`gcs.testing.SimTeam`, and
every one it made is closed when the test ends, passed or failed (simulator,
GCS and their ports). Nothing is imported until a test asks for the fixture:
pytest loads the plugin for every run in the environment.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from gcs.config import Team
    from gcs.testing._simteam import SimTeam

__all__ = ["sim_team"]


@pytest.fixture
def sim_team() -> Iterator[Callable[..., SimTeam]]:
    """``sim_team(config, **options)``: a :class:`gcs.testing.SimTeam` (the same options),
    closed when the test ends."""
    from gcs.testing._simteam import SimTeam

    made: list[SimTeam] = []

    def make(config: str | Path | Team, **options: Any) -> SimTeam:
        team = SimTeam(config, **options)
        made.append(team)
        return team

    yield make
    failures = []
    for team in reversed(made):
        try:
            team.close()
        except Exception as exc:  # close the others all the same
            failures.append(f"{type(exc).__name__}: {exc}")
    if failures:
        raise RuntimeError("closing a SimTeam failed: " + "; ".join(failures))
