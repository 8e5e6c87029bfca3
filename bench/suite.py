"""The project's own test suite on a busy machine: the README's pytest command, timed,
with CPU hogs beside it.

Why: the suite must pass whatever else the machine runs (a developer's laptop, a
shared CI host); a test that fails under load checks the load, not the code. Each
run starts ``--hogs`` processes that keep a core busy each, runs the pytest part of
the README's test command (``.ci/run``'s last line, so the two cannot drift: each of
its pytest commands in turn) and
stops the hogs. Prints a line per run, then one JSON object on the last line:

    {"runs": 3, "hogs": 2, "command": "...", "passed": [true, ...],
     "wall_s": [...], "cpu_s": [...], "reference_s": 0.23, "failed": [[...], ...]}

``cpu_s`` is the CPU time of the suite's processes (the commands and every process
they waited for: workers, simulators, browsers), the hogs' not counted: the work the
suite asks of the machine. ``reference_s`` is the CPU time of a fixed pure-Python
workload measured before the runs, best of five: a shared VM's speed changes
from hour to hour (docs/performance.md, "Measuring it"), so wall and CPU times are
comparable across days only as multiples of it.

Each run's whole output is kept in ``--keep`` (default: a temporary directory, named
on the run's line) for the failures' tracebacks. Exit status 1 unless every run passed.

    python bench/suite.py [--runs 3] [--hogs 2] [--workers 2] [--keep DIR]
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import resource
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from continuity import hogs

ROOT = Path(__file__).resolve().parents[1]


def pytest_commands() -> list[list[str]]:
    """The pytest parts of the test command ``.ci/run`` runs (the README's), in order."""
    last = (ROOT / ".ci" / "run").read_text().strip().splitlines()[-1]
    runs = [argv for argv in (shlex.split(part) for part in last.split("&&")) if "pytest" in argv]
    if not runs:
        raise SystemExit(f"bench/suite.py: no pytest in .ci/run's last line: {last!r}")
    return runs


def with_workers(argv: list[str], workers: int) -> list[str]:
    """``argv`` with its ``-n N`` replaced by ``workers`` (none for 1; as it is for 0, or
    for a command that runs in one process)."""
    if workers <= 0 or "-n" not in argv:
        return argv
    kept = [a for i, a in enumerate(argv) if a != "-n" and (i == 0 or argv[i - 1] != "-n")]
    return kept + (["-n", str(workers)] if workers > 1 else [])


def reference_s() -> float:
    """CPU seconds of a fixed pure-Python workload, the best of five: the machine's
    speed at the moment (its figures on the 2-core VM: docs/performance.md, "Figures" of
    "The project's own suite")."""
    best = float("inf")
    for _ in range(5):
        start = time.process_time()
        table: dict[int, int] = {}
        for i in range(2_000_000):
            table[i % 1009] = table.get(i % 1009, 0) + i * i
        best = min(best, time.process_time() - start)
    return best


def _children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _run(argv: list[str]) -> tuple[int, str, str]:
    """Run one pytest command in a session of its own: stopped early (the bench killed),
    its whole process group goes with it, xdist's workers and what they started too."""
    proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    try:
        stdout, stderr = proc.communicate()
    finally:
        if proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.returncode, stdout, stderr


def run_once(commands: list[list[str]], hog_count: int,
             keep: Path) -> tuple[bool, float, float, list[str]]:
    """One run of the suite (each of ``commands`` in turn, as the README's ``&&`` chain:
    a failed one stops it) beside ``hog_count`` hogs, its output written to ``keep``:
    passed, wall seconds, CPU seconds (the hogs' not counted), failures."""
    busy = hogs(hog_count)
    text, ok = "", True
    try:
        started, cpu0 = time.monotonic(), _children_cpu_s()
        for argv in commands:
            returncode, stdout, stderr = _run(argv)
            text += stdout + stderr
            tail = stdout.strip().splitlines()[-1:] or ["(no output)"]
            print(f"  {shlex.join(argv)}: {tail[0]} (output: {keep})", flush=True)
            if returncode != 0:
                ok = False
                break
        wall, cpu = time.monotonic() - started, _children_cpu_s() - cpu0  # hogs not yet waited
    finally:
        for p in busy:
            p.kill()
            p.wait()
    keep.write_text(text)
    failed = [line.split(" - ")[0] for line in text.splitlines()
              if line.startswith(("FAILED ", "ERROR "))]
    return ok, wall, cpu, failed


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3, help="runs of the whole suite")
    parser.add_argument("--hogs", type=int, default=2, help="CPU hogs beside each run")
    parser.add_argument("--keep", type=Path, default=None,
                        help="directory for each run's output (default: a new temporary one)")
    parser.add_argument("--workers", type=int, default=0,
                        help="pytest-xdist workers instead of the command's (default: as it is;"
                             " 1: one process)")
    args = parser.parse_args()
    # stopped with SIGTERM (kill, a CI timeout): unwind, so the hogs and the suite's run
    # are killed with it instead of loading the machine on their own
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    keep = args.keep or Path(tempfile.mkdtemp(prefix="suite-"))
    keep.mkdir(parents=True, exist_ok=True)
    commands = [with_workers(argv, args.workers) for argv in pytest_commands()]
    command = " && ".join(shlex.join(argv) for argv in commands)
    reference = reference_s()
    print(f"reference workload: {reference:.3f} CPU-s (the machine's speed now)", flush=True)
    summary: dict[str, object] = {"runs": args.runs, "hogs": args.hogs, "command": command}
    passed, walls, cpus, failures = [], [], [], []
    for k in range(args.runs):
        print(f"run {k + 1}/{args.runs}: {command} beside {args.hogs} hog(s)", flush=True)
        ok, wall, cpu, failed = run_once(commands, args.hogs, keep / f"run{k + 1}.log")
        passed.append(ok)
        walls.append(round(wall, 1))
        cpus.append(round(cpu, 1))
        failures.append(failed)
        print(f"run {k + 1}/{args.runs}: {'passed' if ok else 'FAILED'} in {wall:.0f} s "
              f"({wall / reference:.0f} references), {cpu:.0f} CPU-s "
              f"({cpu / reference:.0f} references)"
              + "".join(f"\n  {f}" for f in failed), flush=True)
    summary |= {"passed": passed, "wall_s": walls, "cpu_s": cpus,
                "reference_s": round(reference, 4), "failed": failures}
    print(json.dumps(summary))
    return 0 if all(passed) else 1


if __name__ == "__main__":
    sys.exit(main())
