"""Read a recorded flight (.tlog): its index, the flight as arrays, its metrics and report.

Shows the public API of ``gcs.flightlog``: :class:`TlogIndex` indexes the file
in one compiled pass and decodes only the messages asked for (here the
first STATUSTEXT events); :class:`FlightLog` is the flight as arrays (ticks,
phases, tracks) and gives the metrics ``gcs fly`` printed live, under the same
keys; :func:`write_report` writes what ``gcs report`` writes.

Run from the repository root, on a log of ``examples/02_fly_headless.py``::

    python examples/02_fly_headless.py --record flight.tlog
    python examples/03_read_a_log.py flight.tlog [--out flight_report]

Exit status 2 for a file that cannot be read as a log.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gcs.flightlog import FlightLog, LogError, TlogIndex, write_report


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Read a recorded .tlog and print its figures.")
    parser.add_argument("log", type=Path, help="the .tlog")
    parser.add_argument("--out", metavar="DIR", type=Path,
                        help="also write the report (figures, summary.json, summary.md) here")
    args = parser.parse_args(argv)

    try:
        index = TlogIndex.build(args.log)
        log = FlightLog.load(args.log)
    except (LogError, OSError) as exc:
        print(f"03_read_a_log: error: {exc}", file=sys.stderr)
        return 2

    print(f"{'messages':<24}  {len(index)} from systems {index.systems()}")
    print(f"{'damage':<24}  {index.damage()}")
    for t, msg in index.messages(index.select("STATUSTEXT")[:5]):
        print(f"{'event':<24}  {t - index.t[0]:7.2f} s  system {msg.get_srcSystem()}: "
              f"{msg.text}")

    metrics = log.metrics().to_json() if len(log.tick_t) else log.telemetry_metrics()
    print(f"{'vehicles':<24}  {sorted(log.tracks)}")
    for key in ("duration_s", "ticks", "worst_distance_error_m", "payload_lift_m",
                "worst_bank_rad", "worst_accel_cmd_m_s2"):
        print(f"{key:<24}  {metrics[key]}")
    t0 = log.tick_t[0] if len(log.tick_t) else 0.0
    for t, phase in log.phase_changes():
        print(f"{'phase':<24}  {t - t0:7.2f} s  {phase}")
    for line in log.missing:
        print(f"{'missing':<24}  {line}")

    if args.out is not None:
        summary = write_report(log, args.out)
        print(f"{'report':<24}  {args.out}: {', '.join(summary['figures'])}, "
              f"summary.json, summary.md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
