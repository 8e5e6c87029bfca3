"""``python -m sim``: host a whole simulated team behind MAVLink (zenoh, optionally UDP).

Prints one line once every endpoint is up, e.g.::

    sim ready: fleet default, 4 vehicles, zenoh listen tcp/127.0.0.1:7447, speed 1x

then runs until SIGINT/SIGTERM (or ``--duration``). A bad configuration is
one line on stderr and exit status 2; endpoints that cannot be opened (a
port in use) exit with status 1. See "The sim host" in sim/README.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import logging
import signal
import sys
from collections.abc import Sequence

from gcs.common import ConfigError
from gcs.config import load_team
from gcs.transport import DEFAULT_ENDPOINT
from sim._config import load_world_config
from sim._faults import GUST_MAX_M_S
from sim._host import SimHost
from sim._options import HostOptions
from sim._ready_team import DEFAULT_AUTOPILOT_CONFIG, DEFAULT_WORLD_CONFIG
from sim._udp import DEFAULT_BASE_PORT, DEFAULT_GCS_PORT
from vehicles import load_autopilot_config

__all__ = ["main"]

_BAD_CONFIG = 2
_CANNOT_START = 1
_GIL_SWITCH_S = 1e-4
"""Receive threads wait at most this long for the loop to hand over the GIL (default 5 ms),
so an inbound frame is queued within 0.1 ms even while telemetry is being encoded."""


_MAX = "max"


def _speed(text: str) -> str | float:
    """``"max"`` or a positive number."""
    if text == _MAX:
        return _MAX
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number or 'max', got {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"speed must be positive, got {text}")
    return value


def _gusts(text: str | None) -> float | None:
    """``--gusts``: a gust standard deviation, m/s per axis, 0 up to a gale (None: the
    world's)."""
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0.0 <= value <= GUST_MAX_M_S:  # also NaN
        raise ValueError(f"--gusts: expected 0 to {GUST_MAX_M_S:g} m/s per axis, got {text!r}")
    return value


def _team_json(text: str | None) -> object:
    """The mapping ``--team-json`` gives (None without it); malformed JSON, or JSON that
    is not an object, is one line."""
    if text is None:
        return None
    try:
        value = json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise ValueError(f"--team-json: not JSON ({exc})") from None
    if not isinstance(value, dict):
        raise ValueError(f"--team-json: expected a JSON object, got {type(value).__name__}")
    return value


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m sim",
        description="Simulate a team of quadrotors carrying a payload; every vehicle is a "
                    "MAVLink 2 system on zenoh (and UDP with --udp).")
    p.add_argument("--config", required=True, help="team file, e.g. configs/bebop_square.yaml")
    p.add_argument("--team-json", default=None, metavar="JSON",
                   help="the team's contents as JSON, in place of the file's (a GCS passes a "
                        "team changed in memory this way); relative paths still start from "
                        "the file's directory")
    p.add_argument("--speed", type=_speed, default=None, metavar="N|max",
                   help="sim seconds per wall second (default 1; max with --lockstep)")
    p.add_argument("--lockstep", action="store_true",
                   help="never run more than one guidance period past the GCS's clock ack")
    p.add_argument("--udp", action="store_true",
                   help="also open a MAVLink UDP port per vehicle (SITL style)")
    p.add_argument("--udp-base-port", type=int, default=DEFAULT_BASE_PORT, metavar="P",
                   help=f"UDP port of the team's first vehicle (on P); the others follow "
                        f"in team order on P+1, P+2, ... (default {DEFAULT_BASE_PORT})")
    p.add_argument("--udp-gcs-port", type=int, default=DEFAULT_GCS_PORT, metavar="P",
                   help=f"ground-station port on 127.0.0.1 every vehicle sends to "
                        f"(default {DEFAULT_GCS_PORT}; 0: none, only answer peers)")
    p.add_argument("--listen", action="extend", nargs="+", default=[], metavar="EP",
                   help=f"zenoh endpoints to listen on (default {DEFAULT_ENDPOINT})")
    p.add_argument("--connect", action="extend", nargs="+", default=[], metavar="EP",
                   help="zenoh endpoints to connect to (default none)")
    p.add_argument("--tls", metavar="DIR",
                   help="zenoh over TLS with mutual authentication and access control by "
                        "role, with the certificates `gcs certs DIR` made (ca.pem, sim.pem, "
                        "sim.key); tcp/ endpoints become tls/")
    p.add_argument("--seed", type=int, default=0, help="seed of sensor noise and gusts")
    p.add_argument("--gusts", default=None, metavar="M/S",
                   help="turbulent wind: standard deviation of the gust velocity per axis, m/s "
                        "(a random gust of 2 s correlation, seeded by --seed; default: the "
                        "world's, none)")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="stop after S seconds of sim time (default: run until stopped)")
    p.add_argument("--fleet", default=None,
                   help="fleet name in the zenoh keys (default: the team file's gcs.fleet)")
    p.add_argument("--insecure", action="store_true",
                   help="no MAVLink signing: anyone who reaches a port commands the vehicles "
                        "(default: every vehicle signs with the team key and refuses "
                        "unsigned frames)")
    p.add_argument("--separate-origins", action="store_true",
                   help="give each vehicle its own local origin at its start position, as GPS "
                        "autopilots do (LOCAL_POSITION_NED starts at 0, 0 for every vehicle; "
                        "global positions stay true)")
    p.add_argument("--background", action="store_true",
                   help="paced runs: step at background CPU priority while keeping up, so a "
                        "GCS on the same machine always goes first (Linux; needs root or "
                        "CAP_SYS_NICE, else ignored; a saturated machine slows the sim)")
    return p


def _options(args: argparse.Namespace) -> HostOptions:
    if args.speed is None:
        speed = None if args.lockstep else 1.0
    else:
        speed = None if args.speed == _MAX else float(args.speed)
    return HostOptions(speed=speed, lockstep=args.lockstep,
                       listen=tuple(args.listen) or (DEFAULT_ENDPOINT,),
                       connect=tuple(args.connect), udp=args.udp,
                       udp_base_port=args.udp_base_port, udp_gcs_port=args.udp_gcs_port or None,
                       seed=args.seed, duration=args.duration, fleet=args.fleet,
                       signing=not args.insecure, background=args.background,
                       separate_origins=args.separate_origins, tls=args.tls)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the sim host; returns the exit status."""
    args = _parser().parse_args(argv)
    try:
        options = _options(args)
        team = load_team(args.config, mapping=_team_json(args.team_json))
        world_config = load_world_config(DEFAULT_WORLD_CONFIG)
        gusts = _gusts(args.gusts)
        if gusts is not None:
            world_config = dataclasses.replace(
                world_config, wind=dataclasses.replace(world_config.wind, gust_std=gusts))
        autopilot_config = load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG)
    except (ConfigError, ValueError) as exc:
        print(f"sim: error: {exc}", file=sys.stderr)
        return _BAD_CONFIG
    logging.basicConfig(level=logging.INFO, format="sim: %(message)s", stream=sys.stderr)
    try:
        host = SimHost(team, options, world_config=world_config,
                       autopilot_config=autopilot_config)
    except ConfigError as exc:  # a signing key file named by the team file
        print(f"sim: error: {exc}", file=sys.stderr)
        return _BAD_CONFIG
    except (RuntimeError, OSError) as exc:
        print(f"sim: error: {exc}", file=sys.stderr)
        return _CANNOT_START
    sys.setswitchinterval(_GIL_SWITCH_S)
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: host.stop())
    try:
        print(host.ready_line(), flush=True)
        host.run()
    finally:
        host.close()
    logging.getLogger("sim").info("stopped at t = %.3f s", host.t)
    return 0


if __name__ == "__main__":
    sys.exit(main())
