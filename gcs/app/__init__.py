"""The GCS process assembled, the simulated team as a child, headless flights.

:class:`GcsApp` is what ``gcs run`` and ``gcs demo`` start (links, clock,
operator, recorder and the loop); :class:`SimProcess` starts ``python -m sim``;
:func:`fly` plays a :class:`Scenario` in lockstep with the simulator, or on the
wall clock with the real autopilots a team's ``links:`` reach;
:func:`fly_seeds_in_parallel` flies one simulated flight per seed, N at a time.

Modules:

    ``_app``         The GCS process, assembled: links, clock, operator, recorder and the 4
                     Hz loop.
    ``_fly``         ``gcs fly``: a headless flight of a scenario, simulated or on real
                     autopilots, and its metrics.
    ``_scenario``    Scripted operator inputs: a scenario is a list of steps played through
                     the same operator-command object and phase actions as the browser and
                     the gamepad.
    ``_seeds``       Flights of many seeds in parallel: one lockstep flight per simulator
                     seed, N at a time.
    ``_simfork``     Simulators forked from a warm server: ready in tens of milliseconds,
                     not two seconds.
    ``_simjoin``     Joining a running simulator (``gcs fly --connect``): lockstep or not,
                     and whether it is sound.
    ``_simprocess``  Start the simulated team (``python -m sim``) as a child process and
                     wait until it is up.
    ``_verify``      ``gcs analyze --verify``: fly the team in the simulator and hold the
                     analysis to it.
"""

from gcs.app._app import LOOP_GIL_SWITCH_S, GcsApp
from gcs.app._fly import (
    REAL_PROFILES,
    FlightResult,
    HeadlessFlight,
    flies_real_vehicles,
    fly,
)
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
from gcs.app._seeds import (
    SeedFlight,
    fly_seed,
    fly_seeds_in_parallel,
    jobs_for,
    parse_gusts,
    parse_jobs,
    parse_seeds,
    seed_record,
    seeds_text,
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
    predictions,
    rope_loads,
    verify,
)

__all__ = [
    "FIGURES",
    "LOOP_GIL_SWITCH_S",
    "REAL_PROFILES",
    "Figure",
    "FlightFigures",
    "FlightResult",
    "GcsApp",
    "HeadlessFlight",
    "Row",
    "Scenario",
    "ScenarioError",
    "SeedFlight",
    "SimProcess",
    "SimStartError",
    "Step",
    "Sticks",
    "VerifyResult",
    "check_scenario",
    "compare",
    "flies_real_vehicles",
    "fly",
    "fly_seed",
    "fly_seeds_in_parallel",
    "format_verify",
    "free_tcp_port",
    "jobs_for",
    "load_scenario",
    "measure_flight",
    "parse_gusts",
    "parse_jobs",
    "parse_seeds",
    "play",
    "play_step",
    "predictions",
    "rope_loads",
    "seed_record",
    "seeds_text",
    "verify",
]
