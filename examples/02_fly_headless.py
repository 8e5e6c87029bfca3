"""Fly a scripted flight headless with simulated vehicles and read its metrics.

What ``gcs fly`` does, through the public API of ``gcs.app``: :func:`load_scenario`
reads the operator's inputs, :func:`fly` starts the simulated team
(``python -m sim``) in lockstep with the GCS, plays the scenario, records every
frame to a .tlog and returns a :class:`FlightResult` with the flight's metrics.
The keys printed are those of ``gcs fly --json`` (units in the names).

Run from the repository root (about 40 s of flight, a few times faster than real time)::

    python examples/02_fly_headless.py [--record flight.tlog] [--speed max|N]

Without ``--record`` the log goes to a temporary directory, removed at the end;
``examples/03_read_a_log.py`` reads a kept one. Exit status 1 if the flight did
not complete.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from gcs.app import fly, load_scenario
from gcs.common import shipped_config
from gcs.config import load_team

#: What is printed of the flight's metrics, in this order.
SHOWN = ("completed", "error", "duration_s", "ticks", "worst_distance_error_m",
         "worst_distance_error_by_phase_m", "payload_lift_m", "worst_swing_rad",
         "worst_bank_rad", "worst_accel_cmd_m_s2", "rope_tension_min_N", "rope_tension_max_N",
         "real_time_factor", "phases")


def speed(text: str) -> str:
    """``--speed``: sim seconds per wall second, or ``max`` (as fast as the machine allows)."""
    if text != "max":
        try:
            ok = float(text) > 0
        except ValueError:
            ok = False
        if not ok:
            raise argparse.ArgumentTypeError(f"a positive number or 'max', not {text!r}")
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Fly a scenario headless and print its "
                                                 "metrics.")
    parser.add_argument("--record", metavar="PATH", type=Path,
                        help="keep the .tlog here (default: a temporary directory)")
    parser.add_argument("--speed", type=speed, default="max",
                        help="sim seconds per wall second, or 'max' (default)")
    parser.add_argument("--config", default=str(shipped_config("bebop_square.yaml")),
                        help="team config (default: the shipped bebop_square.yaml)")
    parser.add_argument("--scenario", default=str(shipped_config("scenarios/short_flight.yaml")),
                        help="scenario (default: the shipped scenarios/short_flight.yaml)")
    args = parser.parse_args(argv)

    team = load_team(args.config)
    scenario = load_scenario(args.scenario)
    with tempfile.TemporaryDirectory(prefix="gcs-example-") as tmp:
        record = args.record or Path(tmp) / "flight.tlog"
        result = fly(team, scenario, speed=args.speed, record=record)  # steps go to stderr
        data = result.to_json()
        for key in SHOWN:
            print(f"{key:<32}  {data[key]}")
        size = record.stat().st_size if record.is_file() else 0
        kept = "" if args.record else " (temporary, now removed)"
        print(f"{'record':<32}  {record} {size} bytes{kept}")
    return 0 if result.error is None else 1


if __name__ == "__main__":
    raise SystemExit(main())
