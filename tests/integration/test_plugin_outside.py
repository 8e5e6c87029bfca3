"""The ``sim_team`` fixture in a user's own test suite, from the installed wheel.

The wheel is built and installed into a fresh venv as tests/integration/test_install.py
does (its fixture); a suite is written into an empty directory: the example of
docs/testing.md (arm, take off, lift, sticks, a cut link, a gust, set down,
land, assertions on the metrics) and a test that fails on purpose after
starting a team. The venv's pytest runs it with no checkout on the path: the
plugin comes from the wheel's ``pytest11`` entry point. The example passes, the
failing test's team is closed all the same, and no simulator process or port
is left behind.

The venv's copies of the kernels get the checkout's numba cache first
(:func:`borrow_numba_cache`): compiling them all anew took 85 of this test's
120 s, and the compiling is not what it tests.
"""

from __future__ import annotations

import os
import re
import shutil
import socket
import subprocess
from pathlib import Path

from tests.support.commands import run_outside
from tests.support.paths import ROOT

EXAMPLE = re.compile(r"<!-- the example: [^\n]*-->\n```python\n(.*?)```", re.S)

FAILING = '''
import sys
from pathlib import Path

import pytest

import gcs.testing
from gcs.common import shipped_config


def test_the_package_is_the_wheels():
    assert Path(gcs.testing.__file__).is_relative_to(sys.prefix), gcs.testing.__file__


@pytest.mark.xfail(strict=True, reason="fails on purpose: its team is closed all the same")
def test_a_failing_test_closes_its_team(sim_team):
    team = sim_team(shipped_config("bebop_square.yaml"), seed=2)
    Path("endpoint.txt").write_text(team.endpoint)
    raise AssertionError("on purpose")
'''


def borrow_numba_cache(venv: Path) -> None:
    """Copy the checkout's numba cache beside the venv's copies of the same sources.

    numba keys a cached kernel by its source file's mtime and size, so each copy
    whose bytes are the checkout's takes the checkout's mtime. A kernel whose
    source differs, or a stale checkout cache (the project's fingerprint of the
    kernel sources, copied too, says so), is compiled anew: slower, never wrong.
    """
    (site,) = venv.glob("lib/python*/site-packages")
    for tree in ("gcs", "vehicles", "sim"):
        for cache in (ROOT / tree).rglob("__pycache__"):
            files = [*cache.glob("*.nbi"), *cache.glob("*.nbc"),
                     *cache.glob("numba-sources.sha256")]
            package = site / cache.parent.relative_to(ROOT)
            if not files or not package.is_dir():
                continue
            (package / "__pycache__").mkdir(exist_ok=True)
            for f in files:
                shutil.copy2(f, package / "__pycache__" / f.name)
            for source in cache.parent.glob("*.py"):
                copy = package / source.name
                if copy.is_file() and copy.read_bytes() == source.read_bytes():
                    stat = source.stat()
                    os.utime(copy, ns=(stat.st_atime_ns, stat.st_mtime_ns))


def docs_example() -> str:
    """The complete example of docs/testing.md (the code block after its marker)."""
    found = EXAMPLE.search((ROOT / "docs" / "testing.md").read_text("utf-8"))
    assert found, "docs/testing.md: no example block after its marker"
    return found.group(1)


def test_a_suite_outside_the_checkout_flies_with_the_fixture_and_leaves_nothing_behind(
        installed: tuple[Path, Path]) -> None:
    venv, work = installed
    borrow_numba_cache(venv)
    suite = work / "suite"
    suite.mkdir()
    example = docs_example()
    for call in ("arm()", "lift()", "sticks(", "cut_link(", "gust(", "set_down()", "land()",
                 "metrics()"):
        assert call in example, f"the docs' example no longer shows {call}"
    (suite / "test_carry.py").write_text(example)
    (suite / "test_failing.py").write_text(FAILING)
    done = run_outside([str(venv / "bin" / "python"), "-m", "pytest", "-q", "-p",
                        "no:cacheprovider", "-W",
                        "error::pytest.PytestUnraisableExceptionWarning"],
                       cwd=suite, timeout=600)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "2 passed, 1 xfailed" in done.stdout, done.stdout
    # nothing left: no simulator started from the venv's configs, no port open
    left = subprocess.run(["pgrep", "-af", str(venv)], capture_output=True, text=True,
                          check=False)
    assert left.stdout == "", f"processes left behind:\n{left.stdout}"
    endpoint = (suite / "endpoint.txt").read_text()
    host, port = endpoint.removeprefix("tcp/").rsplit(":", 1)
    with socket.socket() as s:
        s.settimeout(2.0)
        assert s.connect_ex((host, int(port))) != 0, f"{endpoint} still open"
