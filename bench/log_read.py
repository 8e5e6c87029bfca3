"""Opening a flight log of hours: index and load time, peak memory, report time.

Why: the issue asks that a log of hours opens without loading it all into
memory. This bench records one real headless flight (``gcs fly``, the paper's
scenario on the square, every MAVLink frame plus the guidance internals and
sim truth) or takes ``--source``, then tiles it end to end, timestamps
shifted, into a log of ``--hours`` of flight, and opens that in a fresh
process the way ``gcs report`` does: the index (:class:`gcs.flightlog.TlogIndex`),
then the whole :class:`gcs.flightlog.FlightLog`, then the report's figures
and summary. The child first opens the source flight, so its peak memory
before the long log (imports, compiled kernels loaded) is the baseline; the
long log's pages are memory-mapped and counted in the peak as they are read,
so the file's size is printed beside it. Prints a line per stage, then one
JSON object on the last line::

    {"hours": 1.0, "messages": ..., "file_MB": ..., "index_s": ..., "load_s": ...,
     "report_s": ..., "baseline_MB": ..., "loaded_peak_MB": ..., "peak_MB": ...,
     "added_B_per_message": ...}

    python bench/log_read.py [--hours 1] [--source FLIGHT.tlog] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from gcs.flightlog import TlogIndex

__all__ = ["main"]

_ROOT = Path(__file__).resolve().parent.parent

_CHILD = """
import json, resource, sys, time
from pathlib import Path
from gcs.flightlog import FlightLog, TlogIndex, write_report

def peak_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

source, long, out = (Path(a) for a in sys.argv[1:4])
write_report(FlightLog.load(source), out / "source")  # imports and kernels loaded
baseline = peak_mb()
t0 = time.perf_counter()
messages = len(TlogIndex.build(long))  # timed alone, then freed: the load builds its own
t1 = time.perf_counter()
log = FlightLog.load(long)
t2 = time.perf_counter()
loaded = peak_mb()
summary = write_report(log, out / "long")
t3 = time.perf_counter()
print(json.dumps({"messages": messages, "ticks": len(log.tick_t),
                  "duration_s": summary["metrics"]["duration_s"], "index_s": t1 - t0,
                  "load_s": t2 - t1, "report_s": t3 - t2, "baseline_MB": baseline,
                  "loaded_peak_MB": loaded, "peak_MB": peak_mb()}))
"""
"""Runs in a fresh process so its peak memory is the long log's alone."""


def record_flight(path: Path) -> None:
    """Record the paper's flight on the square with ``gcs fly`` (as fast as the sim goes)."""
    cmd = [sys.executable, "-m", "gcs", "fly", "--config", "configs/bebop_square.yaml",
           "--scenario", "configs/scenarios/paper_flight.yaml", "--speed", "max",
           "--record", str(path), "--json"]
    done = subprocess.run(cmd, cwd=_ROOT, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise SystemExit(f"log_read: gcs fly failed (exit {done.returncode}): "
                         f"{done.stderr.strip().splitlines()[-1:]}")


def tile(source: Path, target: Path, hours: float) -> int:
    """Write ``source`` end to end into ``target`` until ``hours`` of log; copies made."""
    index = TlogIndex.build(source)
    if index.skipped_bytes or index.truncated:
        raise SystemExit(f"log_read: {source} is damaged; give a clean recording")
    data = np.fromfile(source, dtype=np.uint8)
    stamp_at = (index.offset - 8)[:, None] + np.arange(8)[None, :]
    t_us = np.round(index.t * 1e6).astype(np.int64)
    span_us = int(t_us.max() - t_us.min()) + 1_000_000
    copies = max(1, int(np.ceil(hours * 3600e6 / span_us)))
    with target.open("wb") as fh:
        for k in range(copies):
            stamps = (t_us + k * span_us).astype(">u8").view(np.uint8).reshape(-1, 8)
            data[stamp_at] = stamps
            data.tofile(fh)
    return copies


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--hours", type=float, default=1.0, help="length of the tiled log, h")
    p.add_argument("--source", type=Path, default=None,
                   help="a recorded flight to tile (default: record one with gcs fly)")
    p.add_argument("--keep", type=Path, default=None, help="keep the logs and reports here")
    args = p.parse_args()
    if args.hours <= 0:
        p.error("--hours must be positive")
    with tempfile.TemporaryDirectory() as scratch:
        work = args.keep or Path(scratch)
        work.mkdir(parents=True, exist_ok=True)
        source = args.source
        if source is None:
            source = work / "flight.tlog"
            print("recording the paper's flight with gcs fly ...", flush=True)
            record_flight(source)
        long = work / "long.tlog"
        copies = tile(source, long, args.hours)
        size_mb = long.stat().st_size / 1e6
        print(f"tiled {copies} copies of {source.name}: {size_mb:.0f} MB", flush=True)
        done = subprocess.run([sys.executable, "-c", _CHILD, str(source), str(long),
                               str(work)], cwd=_ROOT, capture_output=True, text=True,
                              check=False)
        if done.returncode != 0:
            raise SystemExit(f"log_read: opening the long log failed: {done.stderr.strip()}")
        result = json.loads(done.stdout.strip().splitlines()[-1])
    added = (result["loaded_peak_MB"] - result["baseline_MB"]) * 1024 * 1024
    result.update(hours=args.hours, file_MB=size_mb,
                  added_B_per_message=added / result["messages"])
    print(f"{result['messages']} messages, {result['duration_s'] / 3600:.2f} h: index "
          f"{result['index_s']:.2f} s, load {result['load_s']:.2f} s, report "
          f"{result['report_s']:.2f} s; peak memory {result['loaded_peak_MB']:.0f} MB loaded, "
          f"{result['peak_MB']:.0f} MB with the report, over a baseline of "
          f"{result['baseline_MB']:.0f} MB (file {size_mb:.0f} MB)")
    print(json.dumps(result))


if __name__ == "__main__":
    main()
