"""Command-line interface: ``gcs <command>``.

Each command lives in its own function; errors that are the user's (a wrong
config, a missing file) print one line and exit with status 2, never a trace.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from gcs.typed_config import ConfigError

__all__ = ["main"]


def _cmd_analyze(args: argparse.Namespace) -> int:
    from gcs.analysis import analyze, dumps, format_report
    from gcs.config import load_team

    team = load_team(args.config)
    result = analyze(team)
    print(dumps(result) if args.json else format_report(result, team.source))
    return 0 if result.ok else 1


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
    p.set_defaults(func=_cmd_analyze)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``gcs`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except ConfigError as exc:
        print(f"gcs {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
