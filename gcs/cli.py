"""Command-line interface: ``gcs <command>``.

Each command lives in its own function; errors that are the user's (a wrong
config, a missing file) print one line and exit with status 2, never a trace.
"""

from __future__ import annotations

import argparse
import contextlib
import faulthandler
import signal
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from gcs.common import ConfigError, stop_on_signals

if TYPE_CHECKING:
    from gcs.analysis import Analysis
    from gcs.app import Scenario
    from gcs.config import Team
    from gcs.flightlog import FlightLog

__all__ = ["main"]


def _cmd_analyze(args: argparse.Namespace) -> int:
    from gcs.analysis import analysis_json, analyze, format_report
    from gcs.config import load_team

    team = load_team(args.config)
    result = analyze(team)
    if args.verify and (result.ok or result.unchecked_only):
        if not result.ok:
            print(f"gcs analyze: {team.source}: {result.violations[0].message}",
                  file=sys.stderr)
        return _verify(args, team, result)
    print(analysis_json(result) if args.json else format_report(result, team.source))
    return 0 if result.ok else 1


def _verify(args: argparse.Namespace, team: Team, analysis: Analysis) -> int:
    """``gcs analyze --verify``: the team flown once per seed, measured against ``analysis``."""
    import json

    from gcs.app import (
        check_scenario,
        format_verify,
        load_scenario,
        parse_gusts,
        parse_jobs,
        parse_seeds,
        verify,
    )
    from gcs.common import default_config

    scenario = args.scenario or str(default_config("scenarios/paper_flight.yaml"))
    seeds = parse_seeds(args.seeds)
    jobs = parse_jobs(args.jobs)
    gusts = parse_gusts(args.gusts)
    for warning in check_scenario(load_scenario(scenario), team, scenario, analysis=analysis):
        print(f"gcs analyze: warning: {warning}", file=sys.stderr)
    result = verify(team, scenario, analysis, seeds=seeds, jobs=jobs, gusts=gusts,
                    progress=lambda line: print(f"gcs analyze --verify: {line}",
                                                file=sys.stderr, flush=True))
    beyond = [v.term for v in analysis.violations]  # only the team's size (unchecked_only)
    if args.json:
        print(json.dumps({**result.to_json(), "analysis_refuses": beyond}))
    else:
        print(format_verify(result))
        if beyond and result.ok:
            print(f"these flights are the certificate of this team of {analysis.vehicles}, "
                  f"beyond those the analysis is checked on: gcs fly, run and demo fly it "
                  f"with --override-analysis")
    return 0 if result.ok else 1


def _cmd_sim(args: argparse.Namespace) -> int:
    # The simulator is its own program (python -m sim); the GCS never imports it.
    import os

    argv = [sys.executable, "-m", "sim", "--config", args.config, *args.sim_args]
    os.execv(sys.executable, argv)
    return 0  # not reached


def _analysis_refuses(team: Team, command: str, *, override: bool,
                      result: Analysis | None = None) -> bool:
    """True (and every violation on stderr) when ``gcs analyze`` refuses ``team`` (its
    ``result``, computed if not given) and the user did not override it: nothing is
    started for a team the certificate refuses."""
    from gcs.analysis import analyze

    result = result or analyze(team)
    if result.ok or override:
        return False
    print(f"gcs {command}: error: {team.source}: gcs analyze refuses this team "
          f"({len(result.violations)} violation(s)); --override-analysis flies it anyway",
          file=sys.stderr)
    for v in result.violations:
        print(f"  {v.term}: {v.message}", file=sys.stderr)
    return True


def _cmd_key(args: argparse.Namespace) -> int:
    from gcs.config import (
        GcsLinkConfig,
        ensure_team_key,
        key_fingerprint,
        key_from_passphrase,
        load_team,
        team_key_path,
    )
    from gcs.link import LinkError, install_signing_key
    from gcs.wire import write_signing_key

    if args.config:
        team = load_team(args.config)
        path = team_key_path(team.config.gcs, Path(team.source).parent)
    else:
        path = team_key_path(GcsLinkConfig(), Path.cwd())
    if args.passphrase_stdin or args.replace:
        if path.exists() and not args.replace:
            raise ConfigError(str(path), "", "a team key exists already; --replace overwrites "
                              "it (every machine and vehicle then needs the new one)")
        secret = (key_from_passphrase(sys.stdin.readline().rstrip("\n"), "stdin").secret
                  if args.passphrase_stdin else None)
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        path.unlink(missing_ok=True)
        write_signing_key(path, secret=secret)
    key, created = ensure_team_key(path)
    print(f"team key {key_fingerprint(key)} in {path}{' (new)' if created else ''}")
    if args.install:
        if args.sysid is None:
            raise ConfigError("--install", "", "needs --sysid, the vehicle's system id")
        try:
            install_signing_key(args.install, args.sysid, key, component_id=args.component)
        except LinkError as exc:
            print(f"gcs key: error: {exc}", file=sys.stderr)
            return 1
        print(f"vehicle {args.sysid} on {args.install} now signs with team key "
              f"{key_fingerprint(key)}")
    return 0


def _cmd_fly(args: argparse.Namespace) -> int:
    import json
    from pathlib import Path

    from gcs.analysis import analyze
    from gcs.app import (
        check_scenario,
        flies_real_vehicles,
        fly,
        load_scenario,
        parse_gusts,
        parse_jobs,
        parse_seeds,
    )
    from gcs.config import load_team

    seeds = None if args.seeds is None else parse_seeds(args.seeds)
    jobs = parse_jobs(args.jobs)
    gusts = parse_gusts(args.gusts)
    if seeds is None and jobs is not None:
        raise ConfigError("--jobs", "", "is the number of flights of --seeds at a time: "
                          "give --seeds too")
    if seeds is not None and args.connect:
        raise ConfigError("--seeds", "", "each seed is flown on a simulator of its own: "
                          "not with --connect")
    team = load_team(args.config)
    if seeds is not None and flies_real_vehicles(team):
        raise ConfigError("--seeds", "", f"the seeds are the simulator's, and the links of "
                          f"{team.source} reach px4/ardupilot autopilots")
    if args.insecure:
        team = team.without_signing()
    scenario = load_scenario(args.scenario)
    analysis = analyze(team)
    if _analysis_refuses(team, "fly", override=args.override_analysis, result=analysis):
        return 1
    for warning in check_scenario(scenario, team, args.scenario, analysis=analysis):
        print(f"gcs fly: warning: {warning}", file=sys.stderr)
    if args.speed not in (None, "max"):  # None: max, or 1 on real autopilots (gcs.app.fly)
        try:
            if float(args.speed) <= 0:
                raise ValueError
        except ValueError:
            raise ConfigError("--speed", "", f"must be a positive number or 'max', "
                              f"got {args.speed!r}") from None
    if seeds is not None:
        return _fly_seeds(args, team, scenario, seeds, jobs, gusts)
    result = fly(team, scenario, speed=args.speed,
                 record=Path(args.record) if args.record else None, connect=args.connect,
                 progress=not args.quiet, override_analysis=args.override_analysis,
                 gusts=gusts, fork_server=False)  # one simulator: a fork server saves nothing
    data = result.to_json()
    if args.json:
        print(json.dumps(data))
    else:
        width = max(len(k) for k in data)
        for key, value in data.items():
            print(f"{key:<{width}}  {value}")
    return 0 if result.error is None else 1


def _fly_seeds(args: argparse.Namespace, team: Team, scenario: Scenario,
               seeds: tuple[int, ...], jobs: int | None, gusts: float | None) -> int:
    """``gcs fly --seeds``: the scenario flown once per seed, ``jobs`` at a time, and the
    spread of each figure over them (exit 1 if a flight did not complete)."""
    import json

    from gcs.testing import fly_seeds, format_seed_runs

    runs = fly_seeds(team, scenario, seeds, jobs=jobs, speed=args.speed or "max",
                     record=args.record, gusts=gusts,
                     override_analysis=args.override_analysis,
                     progress=None if args.quiet else lambda line: print(
                         f"gcs fly: {line}", file=sys.stderr, flush=True))
    print(json.dumps(runs.to_json()) if args.json else format_seed_runs(runs))
    return 0 if runs.ok else 1


def _load_log(path: Path, command: str, *, quiet: bool) -> FlightLog | None:
    """The flight log at ``path``, with a progress bar per loading stage on stderr.

    Stages: ``index`` (bytes), ``decode`` (the GCS's guidance internals) and
    ``tracks`` (the vehicles' telemetry), in messages. None, after one line on
    stderr, for a file that is no log or cannot be read.
    """
    from tqdm import tqdm

    from gcs.flightlog import FlightLog, LogError

    bars: dict[str, tqdm] = {}

    def progress(stage: str, done: int, total: int) -> None:
        bar = bars.get(stage)
        if bar is None:
            unit = "B" if stage == "index" else "msg"
            bar = bars[stage] = tqdm(total=total, desc=stage, unit=unit, unit_scale=True,
                                     leave=False, file=sys.stderr)
        bar.update(done - bar.n)

    try:
        return FlightLog.load(path, progress=None if quiet else progress)
    except LogError as exc:
        print(f"gcs {command}: error: {exc}", file=sys.stderr)
    except OSError as exc:
        print(f"gcs {command}: error: {_os_error(exc, path)}", file=sys.stderr)
    finally:
        for bar in bars.values():
            bar.close()
    return None


def _cmd_report(args: argparse.Namespace) -> int:
    import json

    from tqdm import tqdm

    from gcs.flightlog import write_report

    path = Path(args.file)
    out = Path(args.out) if args.out else path.with_suffix("").with_name(path.stem + "_report")
    log = _load_log(path, "report", quiet=args.quiet)
    if log is None:
        return 2
    figures = None if args.quiet else tqdm(total=4, desc="figures", unit="fig", leave=False,
                                           file=sys.stderr)
    try:
        summary = write_report(log, out, progress=None if figures is None
                               else lambda _name: figures.update(1))
    except OSError as exc:
        print(f"gcs report: error: {_os_error(exc, out)}", file=sys.stderr)
        return 2
    finally:
        if figures is not None:
            figures.close()
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"report of {path} in {out}/: {', '.join(summary['figures'])}, "
              f"summary.json, summary.md")
        for line in log.missing:
            print(f"missing: {line}")
        damage = log.index.damage()
        if damage is not None:
            print(f"note: {damage}")
        if summary["cut_short"]:
            print(f"note: {summary['cut_short']}")
    return 0


def _os_error(exc: OSError, path: object) -> str:
    """``FILE: cannot read/write (reason)`` in one line, whichever file the error names."""
    return f"{exc.filename or path}: {exc.strerror or exc}"


def _default_team() -> str:
    """configs/bebop_square.yaml here, or the shipped one (run from anywhere)."""
    from gcs.common import default_config

    return str(default_config("bebop_square.yaml"))


def _cmd_demo(args: argparse.Namespace) -> int:
    from pathlib import Path

    from gcs.config import load_team
    from web import run_demo

    config = args.config or _default_team()
    if _analysis_refuses(load_team(config), "demo", override=args.override_analysis):
        return 1
    return run_demo(config, host=args.host, port=args.port,
                    gamepad=Path(args.gamepad) if args.gamepad else None,
                    no_gamepad=args.no_gamepad, insecure=args.insecure,
                    override_analysis=args.override_analysis)


def _cmd_run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from gcs.config import load_team
    from web import run_gcs

    if _analysis_refuses(load_team(args.config), "run", override=args.override_analysis):
        return 1
    return run_gcs(args.config, host=args.host, port=args.port,
                   record=Path(args.record) if args.record else None,
                   gamepad=Path(args.gamepad) if args.gamepad else None,
                   no_gamepad=args.no_gamepad, insecure=args.insecure,
                   override_analysis=args.override_analysis)


def _cmd_replay(args: argparse.Namespace) -> int:
    from web import run_replay

    path = Path(args.file)
    log = _load_log(path, "replay", quiet=args.quiet)
    if log is None:
        return 2
    if args.export is not None:
        from web import run_export

        out = Path(args.export)
        try:
            return run_export(log, out, name=path.name, quiet=args.quiet)
        except OSError as exc:
            print(f"gcs replay: error: {_os_error(exc, out)}", file=sys.stderr)
            return 2
    try:
        return run_replay(log, name=path.name, host=args.host, port=args.port)
    except OSError as exc:
        print(f"gcs replay: error: {_os_error(exc, path)}", file=sys.stderr)
        return 2


def _add_gusts_option(p: argparse.ArgumentParser) -> None:
    """``--gusts`` of the commands that fly the simulator."""
    p.add_argument("--gusts", metavar="M/S",
                   help="turbulence in the simulator: the gusts' standard deviation per "
                        "axis, m/s (e.g. 0.5; random, 2 s correlation, from the seed; "
                        "default calm)")


def _add_page_options(p: argparse.ArgumentParser) -> None:
    """Options shared by the commands that serve the live page."""
    p.add_argument("--port", type=int, default=8080, help="port of the page (default 8080)")
    p.add_argument("--host", default="127.0.0.1",
                   help="interface to serve the page on (default 127.0.0.1: this machine "
                        "only; 0.0.0.0 for every interface)")
    p.add_argument("--gamepad", metavar="FILE",
                   help="gamepad mapping (default: configs/gamepad.yaml in the current "
                        "directory, else the shipped one)")
    p.add_argument("--no-gamepad", action="store_true", help="do not read a gamepad")
    _add_flight_options(p)


def _add_flight_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--override-analysis", action="store_true",
                   help="fly a team that gcs analyze refuses (default: refuse at once, "
                        "listing every violation); each violation stays on the page")
    p.add_argument("--insecure", action="store_true",
                   help="no MAVLink signing on the simulated links: anyone who reaches a "
                        "port can command the vehicles (default: the team key, made on "
                        "first use in the user's config directory)")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="gcs",
        description="Ground-control station for a rigid team of rotorcraft carrying a payload.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("analyze", help="worst-case force analysis of a team config",
                       description="Rope tension, tilt, horizontal force, acceleration limits, "
                                   "the gain condition (eq. max) and the maximum safe "
                                   "deformation of a team. Exit status 1 when the config "
                                   "violates the condition.")
    p.add_argument("config", help="team config (YAML), e.g. configs/bebop_square.yaml")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--verify", action="store_true",
                   help="fly the team through a scenario in the lockstep simulator, once per "
                        "seed, and print measured against predicted per figure (exit 1 when "
                        "a flight exceeds the analysis or does not complete)")
    p.add_argument("--scenario", metavar="S",
                   help="scenario of --verify (default configs/scenarios/paper_flight.yaml)")
    p.add_argument("--seeds", default="1-4", metavar="SEEDS",
                   help="simulator seeds of --verify (sensor noise, gusts): 1-4 (default), "
                        "7, 1,3,9-10")
    p.add_argument("--jobs", metavar="N",
                   help="flights of --verify at a time (default: the machine's cores)")
    _add_gusts_option(p)
    p.set_defaults(func=_cmd_analyze)

    p = sub.add_parser("sim", help="host a simulated team behind zenoh (and UDP)",
                       description="Runs `python -m sim`: the whole simulated team with its "
                                   "INDI autopilots; every vehicle is a MAVLink 2 peer on "
                                   "zenoh (and on UDP with --udp). Options after CONFIG go "
                                   "to the simulator (see `python -m sim --help`).")
    p.add_argument("--config", required=True, help="team config (YAML)")
    # the simulator's options are passed on as they are (main: parse_known_args); a
    # REMAINDER positional refused them, since they start with "--"
    p.set_defaults(func=_cmd_sim, sim_args=[])

    p = sub.add_parser("fly", help="fly a scenario headless, simulated or on real autopilots",
                       description="Starts the simulated team (or joins a running `gcs sim` "
                                   "with --connect), plays the scenario's operator inputs "
                                   "and prints the flight metrics. A team whose links: reach "
                                   "px4/ardupilot autopilots (or their SITL) is flown on "
                                   "them, on the wall clock, with no simulator: payload and "
                                   "rope figures are then null. Exit 1 if the flight did "
                                   "not complete.")
    p.add_argument("--config", required=True, help="team config (YAML)")
    p.add_argument("--scenario", required=True, help="scenario (YAML), e.g. "
                   "configs/scenarios/paper_flight.yaml")
    p.add_argument("--speed", default=None,
                   help="sim seconds per wall second, or 'max' (default); a team whose links "
                        "reach px4/ardupilot autopilots flies at 1 only")
    p.add_argument("--record", metavar="FILE", help="record the flight to a .tlog")
    p.add_argument("--connect", metavar="ENDPOINT",
                   help="join a running `gcs sim` at this zenoh endpoint instead")
    p.add_argument("--seeds", metavar="SEEDS",
                   help="fly once per simulator seed (sensor noise, gusts), e.g. 1-20 or "
                        "1,3,9-10, in parallel, and print the spread of each figure over "
                        "them: min, median, p90, max, mean, worst seed (default: one "
                        "flight, seed 0); with --record FILE each to FILE_seedN.tlog")
    p.add_argument("--jobs", metavar="N",
                   help="flights of --seeds at a time (default: the machine's cores)")
    _add_gusts_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    _add_flight_options(p)
    p.set_defaults(func=_cmd_fly)

    p = sub.add_parser("key", help="the team's MAVLink signing key: show, make, install",
                       description="Every simulated link is signed with the team key, made on "
                                   "first use in the user's config directory; copy the file to "
                                   "fly across machines. --install sends it to a real "
                                   "autopilot (SETUP_SIGNING) and checks that it signs.")
    p.add_argument("--config", help="team config whose gcs.team_key names the file "
                                    "(default: the user's team key)")
    p.add_argument("--passphrase-stdin", action="store_true",
                   help="make the key from a passphrase read from stdin, as MAVProxy's "
                        "'signing key PASSPHRASE' does (SHA-256)")
    p.add_argument("--replace", action="store_true",
                   help="replace an existing key (a fresh random one without "
                        "--passphrase-stdin)")
    p.add_argument("--install", metavar="CONNECTION",
                   help="send the key to a real autopilot over this pymavlink connection "
                        "string (e.g. /dev/ttyACM0, udpin:0.0.0.0:14550), best over USB")
    p.add_argument("--sysid", type=int, help="the autopilot's system id (with --install)")
    p.add_argument("--component", type=int, default=1,
                   help="the autopilot's component id (default 1)")
    p.set_defaults(func=_cmd_key)

    p = sub.add_parser("report", help="figures and summary of a recorded flight",
                       description="Distances and velocities (like the paper's figure), "
                                   "top-view trajectories, distance errors, commanded "
                                   "accelerations against limits, and a JSON/Markdown "
                                   "summary, from a .tlog (ours or a plain autopilot log).")
    p.add_argument("file", help="the .tlog")
    p.add_argument("--out", metavar="DIR", help="output folder (default: <file>_report)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_report)

    p = sub.add_parser("demo", help="simulated team, GCS and live page in one command",
                       description="Starts the simulated team (1x, embedded zenoh, no router), "
                                   "a GCS on the wall clock, as with real vehicles, and the "
                                   "live page; prints the page's address. Ctrl-C stops "
                                   "everything.")
    p.add_argument("--config", default=None,
                   help="team config (default configs/bebop_square.yaml)")
    _add_page_options(p)
    p.set_defaults(func=_cmd_demo)

    p = sub.add_parser("run", help="GCS with its live page for the config's vehicles",
                       description="The GCS on the wall clock for the vehicles the config's "
                                   "links reach (a running `gcs sim`, or real autopilots), "
                                   "with the live page. Ctrl-C stops.")
    p.add_argument("--config", required=True, help="team config (YAML)")
    p.add_argument("--record", metavar="FILE", help="record the flight to a .tlog")
    _add_page_options(p)
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser("replay", help="replay a recorded flight on the page, with a timeline",
                       description="The live page fed from a .tlog (ours or a plain autopilot "
                                   "log): play, pause, speed, scrub, jump to phase changes and "
                                   "warnings. Prints the page's address; Ctrl-C stops.")
    p.add_argument("file", help="the .tlog")
    p.add_argument("--port", type=int, default=8080, help="port of the page (default 8080)")
    p.add_argument("--host", default="127.0.0.1",
                   help="interface to serve the page on (default 127.0.0.1)")
    p.add_argument("--quiet", action="store_true", help="no progress bars while loading")
    p.add_argument("--export", metavar="FILE.html",
                   help="write the replay (scene, plots, timeline) as one HTML file that "
                        "opens in a browser with no server and no network, instead of "
                        "serving it")
    p.set_defaults(func=_cmd_replay)
    _add_certs_parser(sub)
    return parser


def _cmd_certs(args: argparse.Namespace) -> int:
    from gcs.transport import make_team_certificates

    files = make_team_certificates(args.dir, args.hosts, force=args.force, days=args.days)
    print(f"team CA and certificates for sim, gcs, viewer in {Path(args.dir).resolve()}:")
    for path in files:
        print(f"  {path.name}")
    print("copy ca.pem and a role's .pem and .key to each machine (keep ca.key off them); "
          "start with `gcs sim --tls DIR` and `gcs: {zenoh: {tls: {dir: DIR}}}`")
    return 0


def _add_certs_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("certs", help="make the team's TLS certificates for zenoh (CA, sim, "
                                     "gcs, viewer)",
                       description="Writes a CA and a certificate per role (sim, gcs, "
                                   "viewer; EC P-256, keys mode 0600) into DIR, for zenoh "
                                   "over TLS with mutual authentication and access control "
                                   "by role. Never overwrites without --force.")
    p.add_argument("dir", metavar="DIR", help="folder to write them into (made if absent)")
    p.add_argument("--hosts", nargs="+", default=[], metavar="HOST",
                   help="host names and IP addresses the peers connect to (localhost, "
                        "127.0.0.1 and ::1 are always in)")
    p.add_argument("--days", type=int, default=1825,
                   help="validity of the role certificates, days (default 1825; the CA "
                        "twice that)")
    p.add_argument("--force", action="store_true",
                   help="replace existing certificates (a new CA: every machine then needs "
                        "the new files)")
    p.set_defaults(func=_cmd_certs)


def _tell_where_on_sigusr1() -> None:
    """``kill -USR1 PID``: a stuck gcs prints every thread's stack on stderr. Not where
    stderr is no file (main() called in a process whose stderr is captured in memory)."""
    if not hasattr(signal, "SIGUSR1"):
        return
    with contextlib.suppress(AttributeError, ValueError, OSError):  # no fileno
        faulthandler.register(signal.SIGUSR1, all_threads=True)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``gcs`` console script."""
    _tell_where_on_sigusr1()
    stop_on_signals()
    parser = build_parser()
    args, rest = parser.parse_known_args(argv)
    if args.command == "sim":
        args.sim_args = rest  # python -m sim checks them
    elif rest:
        parser.error(f"unrecognized arguments: {' '.join(rest)}")
    try:
        return int(args.func(args))
    except ConfigError as exc:
        print(f"gcs {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except RuntimeError as exc:
        from gcs.app import SimStartError  # loaded already by a command that starts one

        if not isinstance(exc, SimStartError):
            raise
        print(f"gcs {args.command}: error: {exc}", file=sys.stderr)  # one line, no traceback
        return 1


if __name__ == "__main__":
    sys.exit(main())
