"""Ground-control station for a rigid team of rotorcraft carrying one payload.

The subpackages, lowest layer first (each imports only those before it):

==================  ======================================================================
``gcs.common``      typed YAML configs, the shipped config files, the numba cache check
``gcs.wire``        MAVLink 2 on the wire: dialect, framing, signing, setpoints, telemetry,
                    mode numbers, zenoh key names, the clock and sim-truth formats
``gcs.transport``   moving frames: zenoh sessions and transports, pymavlink connections
``gcs.formation``   the formation's graph, rigidity and motion synthesis
``gcs.config``      a team file, validated: shape, gains, limits, payload, links
``gcs.guidance``    the guidance law (eq. udi)
``gcs.analysis``    the worst-case analysis of a team (``gcs analyze``)
``gcs.link``        one MAVLink link per vehicle, autopilot profiles, discovery
``gcs.loop``        the 4 Hz loop: fleet table, safety rules, operator, phases, runtime
``gcs.flightlog``   the recorder, log index and decoding, flight metrics, reports
``gcs.app``         the GCS process assembled, the simulator as a child, headless flights
``gcs.testing``     for integration tests: other hosts (network namespaces), lossy links
``gcs.cli``         the ``gcs`` command
==================  ======================================================================

Importing :mod:`gcs` loads none of them: ``gcs.<name>`` loads one on first use.
"""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["analysis", "app", "cli", "common", "config", "flightlog", "formation", "guidance",
           "link", "loop", "testing", "transport", "wire"]


def __getattr__(name: str) -> ModuleType:
    if name in __all__:
        return importlib.import_module(f"gcs.{name}")
    raise AttributeError(f"module 'gcs' has no attribute {name!r}")
