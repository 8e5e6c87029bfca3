"""Physics of the team: quadrotors, ropes, payload, ground, sensors.

Modules:

    ``__main__``      ``python -m sim``: host a whole simulated team behind MAVLink (zenoh,
                      optionally UDP).
    ``_backend``      What a simulation host (the zenoh/MAVLink sim process) needs from a
                      physics backend.
    ``_config``       World configuration: integration rate, ropes, payload drag, ground,
                      wind, sensors, and where on Earth the world lies.
    ``_dynamics``     Equations of motion of the world: one physics step of every vehicle
                      and the payload.
    ``_fabric``       The sim host's side of zenoh: vehicle links and tokens, clock, truth,
                      acks and control.
    ``_forkserver``  ``python -m sim._forkserver FD``: start simulators by forking a process
                      that is warm.
    ``_faults``       The sim's control topic: test hooks that break a vehicle on purpose.
    ``_ground``       Penalty contact with flat ground for one point (a rotor's footprint or
                      the payload).
    ``_host``         The sim host: one process running the whole team and speaking MAVLink
                      for every vehicle.
    ``_inbox``        Everything that reaches the sim host from other threads, in arrival
                      order.
    ``_layout``       Start layouts of a team around its payload: positions, rope lengths,
                      payload position.
    ``_lifter``       The watchdog process that lifts a starved background stepping thread.
    ``_options``      Options of one sim host run (the ``python -m sim`` flags, as a typed
                      value).
    ``_pacing``       Pacing of sim time against wall time: N times real time, or as fast as
                      possible.
    ``_physics``      The stepping loops: many physics steps, with or without the
                      autopilots.
    ``_priority``     A sim's stepping thread in the background while it keeps up with wall
                      time (opt-in).
    ``_ready_team``   Ready-made teams: default config files, world plus autopilots, a
                      blocking take-off.
    ``_ropes``        Massless rope between a vehicle's centre of mass and the payload.
    ``_sensors``      Simulated sensors: IMU (accelerometer, gyro) and motion-capture pose.
    ``_state``        Arrays of the physics kernel: the world's true state and its
                      constants.
    ``_team_layout``  Where a team starts: its desired shape on the ground around the NED
                      origin.
    ``_udp``          Plain MAVLink over UDP for each simulated vehicle, as an autopilot's
                      SITL offers it.
    ``_wind``         Uniform wind: constant mean plus a first-order (Ornstein-Uhlenbeck)
                      gust.
    ``_world``        The simulated world: N quadrotors on ropes to one payload, ground,
                      wind, sensors.
"""

from sim._backend import PhysicsBackend
from sim._config import HomeConfig, WorldConfig, load_world_config
from sim._faults import ControlAction, ControlCommand, parse_control
from sim._host import LIFT_LAG_S
from sim._layout import Layout, paper_square, ring_layout
from sim._priority import BackgroundStepping
from sim._ready_team import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    build_team,
    take_off,
)
from sim._world import World

__all__ = [
    "DEFAULT_AIRFRAME",
    "DEFAULT_AUTOPILOT_CONFIG",
    "DEFAULT_WORLD_CONFIG",
    "LIFT_LAG_S",
    "BackgroundStepping",
    "ControlAction",
    "ControlCommand",
    "HomeConfig",
    "Layout",
    "PhysicsBackend",
    "World",
    "WorldConfig",
    "build_team",
    "load_world_config",
    "paper_square",
    "parse_control",
    "ring_layout",
    "take_off",
]
