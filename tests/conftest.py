"""The suite's fixtures and hooks: a second host, one recorded short flight, the project's
wheel installed in a venv, and how the suite is scheduled (:mod:`tests.support.scheduling`).
Every folder's tests get them; what the tests share that is not a fixture is in
:mod:`tests.support`."""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import site
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from gcs.testing import Host, NetnsUnavailableError
from tests.support.commands import run_gcs, run_outside
from tests.support.paths import ROOT, SHORT, SQUARE
from tests.support.scheduling import (
    WARMING,
    compile_sources,
    scheduled_first,
    shared_fixture_group,
    wait_for_warm_up,
    warm_kernels,
)

_CONFIG_HOMES: list[str] = []
_WARM_UPS: list[subprocess.Popen[bytes]] = []
_warm = False


def pytest_runtest_setup(item: pytest.Item) -> None:
    """A worker's first test waits for the kernels' warm-up (started by
    :func:`~tests.support.scheduling.warm_kernels`)."""
    global _warm
    path = os.environ.get(WARMING)
    if not _warm and path:
        _warm = True
        wait_for_warm_up(path)


def pytest_configure(config: pytest.Config) -> None:
    """The suite's own user config directory: its team key (made on first use by the GCS
    and the simulators the tests start, which inherit it) never touches the user's. Made
    here, not on import: a process that imports a test module (a spawned worker) would
    leave one behind."""
    home = tempfile.mkdtemp(prefix="gcs-tests-config-")
    _CONFIG_HOMES.append(home)
    os.environ["XDG_CONFIG_HOME"] = home
    warm_up = warm_kernels(config, home)
    if warm_up is not None:
        _WARM_UPS.append(warm_up)
    compile_sources(config)  # meanwhile, on the other core


def pytest_unconfigure(config: pytest.Config) -> None:
    while _WARM_UPS:  # long done by now: reaped, or stopped if it hangs
        warm_up = _WARM_UPS.pop()
        try:
            warm_up.wait(5)
        except subprocess.TimeoutExpired:
            warm_up.kill()
            warm_up.wait()
    while _CONFIG_HOMES:
        shutil.rmtree(_CONFIG_HOMES.pop(), ignore_errors=True)


@pytest.hookimpl(tryfirst=True)  # before pytest-xdist reads the groups into the node ids
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if item.get_closest_marker("xdist_group") is None:
            group = shared_fixture_group(item)
            if group is not None:
                item.add_marker(pytest.mark.xdist_group(group))
    items.sort(key=lambda item: not scheduled_first(item))  # stable: file order otherwise


@pytest.fixture
def other_host() -> Iterator[Host]:
    """A second host (a network namespace); the test is skipped, saying why, where this
    machine cannot make one."""
    try:
        host = Host()
    except NetnsUnavailableError as exc:
        pytest.skip(f"no second host on this machine: {exc}")
    with host:
        yield host


@pytest.fixture(scope="session")
def short_flight(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, Path]:
    """``gcs fly --json --record`` of the short scenario: its metrics and its .tlog.

    Flown once per test session (about 10 s of CPU): the report and the replay tests
    read the same recording, and the workers of one pytest-xdist session share it (the
    first to need it flies it; the others wait for it under a file lock).
    """
    base = tmp_path_factory.getbasetemp()
    shared = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base  # this session's
    lock_path, done = shared / "short_flight.lock", shared / "short_flight.json"
    with open(lock_path, "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not done.exists():
            log = shared / "short_flight.tlog"
            out = run_gcs("fly", "--config", SQUARE, "--scenario", SHORT, "--json",
                          "--record", str(log))
            assert out.returncode == 0, out.stdout + out.stderr
            done.write_text(json.dumps([json.loads(out.stdout.splitlines()[-1]), str(log)]))
        metrics, log_path = json.loads(done.read_text())
    return metrics, Path(log_path)


@pytest.fixture(scope="session")
def installed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """(venv, an empty working directory) with the project's wheel installed in the venv:
    built once for the session (tests/integration/test_install.py and
    test_plugin_outside.py)."""
    base = tmp_path_factory.mktemp("install")
    source, wheels, venv, work = (base / d for d in ("source", "wheels", "venv", "work"))
    work.mkdir()
    # built from a copy: setuptools writes build/ and *.egg-info beside the sources
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".git", "build", "*.egg-info", "__pycache__", ".*_cache", "out", "*.tlog"))
    done = run_outside([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                        "--no-build-isolation", "-w", str(wheels), str(source)],
                       cwd=base, timeout=300)
    assert done.returncode == 0, done.stderr
    wheel = next(wheels.glob("formation_gcs-*.whl"))
    done = run_outside([sys.executable, "-m", "venv", "--without-pip", str(venv)], cwd=base)
    assert done.returncode == 0, done.stderr
    # the dependencies: this environment's site directories, after the venv's own (a
    # path line in a .pth; .pth files inside them, this checkout's editable hook among
    # them, are not run). --system-site-packages would give the base interpreter's
    # instead when this one is itself a venv.
    (inner,) = venv.glob("lib/python*/site-packages")
    outer = [*site.getsitepackages(), site.getusersitepackages()]
    (inner / "outer-environment.pth").write_text(
        "".join(f"{d}\n" for d in outer if Path(d).is_dir()))
    done = run_outside([sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python"),
                        "install", "--quiet", "--no-deps", str(wheel)], cwd=base)
    assert done.returncode == 0, done.stderr
    return venv, work
