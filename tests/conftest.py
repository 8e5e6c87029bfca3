"""What several test files share: the ``gcs`` command line and one recorded short flight."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

SQUARE = "configs/bebop_square.yaml"
SHORT = "configs/scenarios/short_flight.yaml"


def run_gcs(*args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    """``python -m gcs ARGS`` in a subprocess, output captured, never raising on exit status."""
    return subprocess.run([sys.executable, "-m", "gcs", *args], capture_output=True, text=True,
                          timeout=timeout, check=False)


@pytest.fixture(scope="session")
def short_flight(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, Path]:
    """``gcs fly --json --record`` of the short scenario: its metrics and its .tlog.

    Flown once per test session (about 40 s): the report and the replay tests read the
    same recording.
    """
    log = tmp_path_factory.mktemp("flight") / "short.tlog"
    out = run_gcs("fly", "--config", SQUARE, "--scenario", SHORT, "--json", "--record", str(log))
    assert out.returncode == 0, out.stdout + out.stderr
    return json.loads(out.stdout.splitlines()[-1]), log
