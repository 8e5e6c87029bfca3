"""Physics of the team: quadrotors, ropes, payload, ground, sensors.

Modules:

    ``__main__``      ``python -m sim``: host a whole simulated team behind MAVLink (zenoh,
                      optionally UDP).
    ``_backend``      What a simulation host (the zenoh/MAVLink sim process) needs from a
                      physics backend.
    ``_config``       World configuration: integration rate, ropes, payload drag, ground,
                      wind, sensors.
    ``_dynamics``     Equations of motion of the world: one physics step of every vehicle
                      and the payload.
    ``_fabric``       The sim host's side of zenoh: vehicle links and tokens, clock, truth,
                      acks and control.
    ``_faults``       The sim's control topic: test hooks that break a vehicle on purpose.
    ``_ground``       Penalty contact with flat ground for one point (a rotor's footprint or
                      the payload).
    ``_host``         The sim host: one process running the whole team and speaking MAVLink
                      for every vehicle.
    ``_inbox``        Everything that reaches the sim host from other threads, in arrival
                      order.
    ``_layout``       Start layouts of a team around its payload: positions, rope lengths,
                      payload position.
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
from sim._config import (
    GroundConfig,
    RopeConfig,
    SensorConfig,
    WindConfig,
    WorldConfig,
    load_world_config,
)
from sim._dynamics import physics_step
from sim._fabric import CONTROL_TOPIC, TRUTH_TOPIC, HostFabric
from sim._faults import ControlAction, ControlCommand, parse_control
from sim._ground import contact_force
from sim._host import CHUNK_S, CLOCK_REPUBLISH_S, TRUTH_PERIOD_S, SimHost, VehicleStatus
from sim._inbox import ClockAck, ControlMessage, Event, Inbox, Received, Stop
from sim._layout import Layout, paper_square, ring_layout
from sim._options import HostOptions
from sim._pacing import MAX_LAG_S, Pacer
from sim._physics import run_lockstep, run_physics, samples_in
from sim._priority import (
    STAY_LIFTED_S,
    WATCH_PERIOD_S,
    BackgroundStepping,
    can_lift,
    set_background,
)
from sim._ready_team import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    build_team,
    take_off,
)
from sim._ropes import rope_tension
from sim._sensors import sample_imu, sample_pose
from sim._state import PhysicsParams, PhysicsState, make_physics_params, make_physics_state
from sim._team_layout import team_layout
from sim._udp import DEFAULT_BASE_PORT, DEFAULT_GCS_PORT, MAX_PEERS, UdpPorts
from sim._wind import gust_step
from sim._world import World

__all__ = [
    "CHUNK_S",
    "CLOCK_REPUBLISH_S",
    "CONTROL_TOPIC",
    "DEFAULT_AIRFRAME",
    "DEFAULT_AUTOPILOT_CONFIG",
    "DEFAULT_BASE_PORT",
    "DEFAULT_GCS_PORT",
    "DEFAULT_WORLD_CONFIG",
    "MAX_LAG_S",
    "MAX_PEERS",
    "STAY_LIFTED_S",
    "TRUTH_PERIOD_S",
    "TRUTH_TOPIC",
    "WATCH_PERIOD_S",
    "BackgroundStepping",
    "ClockAck",
    "ControlAction",
    "ControlCommand",
    "ControlMessage",
    "Event",
    "GroundConfig",
    "HostFabric",
    "HostOptions",
    "Inbox",
    "Layout",
    "Pacer",
    "PhysicsBackend",
    "PhysicsParams",
    "PhysicsState",
    "Received",
    "RopeConfig",
    "SensorConfig",
    "SimHost",
    "Stop",
    "UdpPorts",
    "VehicleStatus",
    "WindConfig",
    "World",
    "WorldConfig",
    "build_team",
    "can_lift",
    "contact_force",
    "gust_step",
    "load_world_config",
    "make_physics_params",
    "make_physics_state",
    "paper_square",
    "parse_control",
    "physics_step",
    "ring_layout",
    "rope_tension",
    "run_lockstep",
    "run_physics",
    "sample_imu",
    "sample_pose",
    "samples_in",
    "set_background",
    "take_off",
    "team_layout",
]
