"""``bench/fuzz.py`` runs every entry point and reports its counts as one JSON line.

The bench runs 10^6 inputs per entry point by hand; here a few hundred, so
that it keeps working: every entry point fed, no property violated, nothing
on stderr, the counts on the last line.
"""

from __future__ import annotations

import json
import subprocess
import sys

from tests.support.paths import ROOT

ENTRY_POINTS = {"sim_control", "clock", "sim_truth", "gcs_frames", "vehicle_endpoint",
                "telemetry"}


def test_the_fuzz_bench_feeds_every_entry_point_and_counts_the_outcomes() -> None:
    out = subprocess.run([sys.executable, "bench/fuzz.py", "--count", "300", "--seed", "5"],
                         cwd=ROOT, capture_output=True, text=True, timeout=300, check=False)
    assert out.returncode == 0, out.stdout + out.stderr
    assert out.stderr == ""
    report = json.loads(out.stdout.splitlines()[-1])
    assert set(report["entry_points"]) == ENTRY_POINTS
    assert report["violations"] == 0 and report["stderr_bytes"] == 0
    for name, tally in report["entry_points"].items():
        assert tally["inputs"] == 300 and tally["violations"] == 0, (name, tally)
        assert tally["accepted"] > 0 and tally["refused"] > 0, (name, tally)
