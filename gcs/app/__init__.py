"""The GCS process assembled, the simulated team as a child, headless flights.

:class:`GcsApp` is what ``gcs run`` and ``gcs demo`` start (links, clock,
operator, recorder and the loop); :class:`SimProcess` starts ``python -m sim``;
:func:`fly` plays a :class:`Scenario` in lockstep with the simulator.

Modules:

    ``_app``         The GCS process, assembled: links, clock, operator, recorder and the 4
                     Hz loop.
    ``_fly``         ``gcs fly``: a headless flight of a scenario with simulated vehicles,
                     and its metrics.
    ``_scenario``    Scripted operator inputs: a scenario is a list of steps played through
                     the same operator-command object and phase actions as the browser and
                     the gamepad.
    ``_simprocess``  Start the simulated team (``python -m sim``) as a child process and
                     wait until it is up.
    ``_verify``      ``gcs analyze --verify``: fly the team in the simulator and hold the
                     analysis to it.
"""

from gcs.app._app import LOOP_GIL_SWITCH_S, GcsApp
from gcs.app._fly import FlightResult, HeadlessFlight, fly
from gcs.app._scenario import (
    Scenario,
    ScenarioError,
    Step,
    Sticks,
    check_scenario,
    load_scenario,
    play,
    play_step,
)
from gcs.app._simprocess import SimProcess, SimStartError, free_tcp_port
from gcs.app._verify import (
    FIGURES,
    Figure,
    FlightFigures,
    Row,
    VerifyResult,
    compare,
    format_verify,
    measure_flight,
    parse_seeds,
    predictions,
    rope_loads,
    verify,
)

__all__ = [
    "FIGURES",
    "LOOP_GIL_SWITCH_S",
    "Figure",
    "FlightFigures",
    "FlightResult",
    "GcsApp",
    "HeadlessFlight",
    "Row",
    "Scenario",
    "ScenarioError",
    "SimProcess",
    "SimStartError",
    "Step",
    "Sticks",
    "VerifyResult",
    "check_scenario",
    "compare",
    "fly",
    "format_verify",
    "free_tcp_port",
    "load_scenario",
    "measure_flight",
    "parse_seeds",
    "play",
    "play_step",
    "predictions",
    "rope_loads",
    "verify",
]
