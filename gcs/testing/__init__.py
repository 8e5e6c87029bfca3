"""Tools for integration tests: a simulated team flown from Python, its pytest fixture, other
hosts, lossy links, raw MAVLink frames.

:class:`SimTeam` flies a simulated team headless, one call per step, in lockstep
on the simulator's clock (``docs/testing.md``); the ``sim_team`` pytest fixture
(the ``formation_gcs`` plugin, registered by the package's entry points) makes
them and closes them after each test; :meth:`Team.connect` flies the real
autopilots a team file's ``links:`` reach with the same calls, on the wall clock.
:func:`fly_seeds` flies a scenario once per simulator seed, in parallel, and
summarises each figure over the seeds.

Modules:

    ``_frames``   MAVLink 2 frames around any payload, and where each field of a message
                  sits in it.
    ``_mavutil``  The team key, and pymavlink connections in MAVLink 2 (signed with it).
    ``_metrics``  The figures of a flight, as ``gcs fly --json`` prints them, as attributes
                  to assert on.
    ``_netns``    A second host on this machine: a network namespace joined to this one by a
                  veth pair.
    ``_plugin``   The pytest plugin ``formation_gcs``: a ``sim_team`` fixture for a user's own
                  test suite.
    ``_relay``    A TCP relay that delays and stalls a stream as a lossy radio link would.
    ``_seedruns`` Monte-Carlo flights: one scenario flown once per simulator seed, and the
                  spread of each figure over them (``gcs fly --seeds``, ``fly_seeds``).
    ``_simteam``  A simulated team flown from Python, for integration tests: ``SimTeam``.
    ``_team``     A team flown from Python one call per step, simulated or real: ``Team``
                  (``Team.connect`` for real autopilots).

Each name loads its module on first use: pytest imports this package (for the
plugin) in every run of every test suite where formation-gcs is installed, and
``SimTeam`` alone pulls in the whole GCS.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from gcs.testing._frames import field_layout, raw_frame
    from gcs.testing._mavutil import mavlink2_connection, signed_connection, team_key
    from gcs.testing._metrics import Metrics
    from gcs.testing._netns import Host, NetnsUnavailableError
    from gcs.testing._relay import RTO_S, LossyRelay
    from gcs.testing._seedruns import (
        LESS_IS_WORSE,
        SeedRun,
        SeedRuns,
        Spread,
        fly_seeds,
        format_seed_runs,
        spread,
    )
    from gcs.testing._simteam import SimTeam
    from gcs.testing._team import FlightError, FlightEvent, SimulatorOnlyError, Team, TeamState

__all__ = [
    "LESS_IS_WORSE",
    "RTO_S",
    "FlightError",
    "FlightEvent",
    "Host",
    "LossyRelay",
    "Metrics",
    "NetnsUnavailableError",
    "SeedRun",
    "SeedRuns",
    "SimTeam",
    "SimulatorOnlyError",
    "Spread",
    "Team",
    "TeamState",
    "field_layout",
    "fly_seeds",
    "format_seed_runs",
    "mavlink2_connection",
    "raw_frame",
    "signed_connection",
    "spread",
    "team_key",
]

_MODULE = {
    "field_layout": "_frames", "raw_frame": "_frames",
    "mavlink2_connection": "_mavutil", "signed_connection": "_mavutil",
    "team_key": "_mavutil",
    "Metrics": "_metrics",
    "Host": "_netns", "NetnsUnavailableError": "_netns",
    "RTO_S": "_relay", "LossyRelay": "_relay",
    "LESS_IS_WORSE": "_seedruns", "SeedRun": "_seedruns", "SeedRuns": "_seedruns",
    "Spread": "_seedruns",
    "fly_seeds": "_seedruns", "format_seed_runs": "_seedruns", "spread": "_seedruns",
    "SimTeam": "_simteam",
    "FlightError": "_team", "FlightEvent": "_team", "SimulatorOnlyError": "_team",
    "Team": "_team", "TeamState": "_team",
}
"""The module each public name lives in."""


def __getattr__(name: str) -> Any:
    module = _MODULE.get(name)
    if module is None:
        raise AttributeError(f"module 'gcs.testing' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"gcs.testing.{module}"), name)
    globals()[name] = value  # found directly from now on
    return value
