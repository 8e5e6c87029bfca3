"""Every bench (``bench/*.py``) answers ``--help`` with its usage and nothing else.

The benches are run by hand, rarely; ``--help`` is how one learns their options,
so it must not run the bench, print a traceback or warn. A new bench is covered
as soon as it is in ``bench/``.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCHES = sorted((ROOT / "bench").glob("*.py"))


def test_there_are_benches_to_check() -> None:
    assert BENCHES, f"no bench/*.py under {ROOT}"


@pytest.mark.parametrize("bench", BENCHES, ids=[p.name for p in BENCHES])
def test_a_bench_prints_its_usage_on_help(bench: Path) -> None:
    out = subprocess.run([sys.executable, str(bench.relative_to(ROOT)), "--help"], cwd=ROOT,
                         capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stdout + out.stderr
    assert out.stdout.startswith(f"usage: {bench.name}"), out.stdout
    assert out.stderr == "", out.stderr
