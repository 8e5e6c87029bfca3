"""How the suite is scheduled (the hooks in ``tests/conftest.py`` call these): the project
compiled and the test modules rewritten once, the simulator's kernels warmed before the
workers start, the tests sharing a fixture grouped on one worker, the long ones first."""

from __future__ import annotations

import compileall
import fcntl
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.support.paths import ROOT

PACKAGES = ("gcs", "sim", "vehicles", "web")
"""The project's packages, which the processes the suite starts import."""


def suite_modules(tests: Path = ROOT / "tests") -> list[Path]:
    """The modules pytest rewrites the asserts of, in every folder of ``tests``: the
    conftest files, the helpers of ``tests/support`` and the test modules."""
    return sorted([*tests.rglob("conftest.py"), *(tests / "support").rglob("*.py"),
                   *tests.rglob("test_*.py")])


def compile_sources(config: pytest.Config) -> None:
    """Write the bytecode of :data:`PACKAGES`, and of the test modules as pytest rewrites
    their asserts, once, in the controller, before the workers start (about 4 s): on a
    fresh checkout the four workers each rewrote every test module at once (3.6 s of CPU
    apiece), and where Python is told not to write bytecode (PYTHONDONTWRITEBYTECODE, as
    in some CI sandboxes) each of the hundred-odd Python processes the suite starts
    compiled the project's sources again (0.2 s apiece) and each pytest run rewrote the
    tests again."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        return
    for package in PACKAGES:
        compileall.compile_dir(ROOT / package, quiet=1)
    cache_rewritten(config, suite_modules())


def cache_rewritten(config: pytest.Config, modules: list[Path]) -> None:
    """Write pytest's cache of MODULES with their asserts rewritten, which pytest reads even
    where it may not write it. Through pytest's private API: where that has changed, each
    process rewrites the modules itself as before."""
    try:
        from _pytest.assertion import rewrite
        state = config.stash[rewrite.assertstate_key]
        for module in modules:
            cache = rewrite.get_cache_dir(module)
            pyc = cache / (module.name[:-3] + rewrite.PYC_TAIL)
            if rewrite._read_pyc(module, pyc, state.trace) is None and \
                    rewrite.try_makedirs(cache):
                source_stat, code = rewrite._rewrite_test(module, config)
                rewrite._write_pyc(state, code, source_stat, pyc)
    except (ImportError, AttributeError, KeyError, TypeError, OSError, SyntaxError):
        return


WARMING = "GCS_TESTS_WARMING"
"""Environment variable naming the lock file the kernels' warm-up holds while it runs."""
WARM_WAIT_S = 300.0
"""A worker waits this long at most for the warm-up, s (then each process compiles)."""


def warm_kernels(config: pytest.Config, directory: str) -> subprocess.Popen[bytes] | None:
    """Start compiling the simulator's numba kernels before the workers start (with
    ``-n``): on a fresh checkout (CI) every worker's simulator fork server, every
    simulator started cold and every in-process world of the first minute compiled them
    at once, about 15 s of CPU apiece. The workers start and collect meanwhile (about 7
    s of CPU each), and wait for it before their first test (``pytest_runtest_setup`` in
    ``tests/conftest.py``). Loaded from the cache, about 1 s. A failure here only leaves
    each process to compile what it needs. Returns the warm-up's process (None: not
    started)."""
    if os.environ.get("PYTEST_XDIST_WORKER") or not config.getoption("numprocesses", None):
        return None
    lock = Path(directory) / "warming.lock"
    with open(lock, "w") as held:
        fcntl.flock(held, fcntl.LOCK_EX)  # the warm-up's copy holds it until it exits
        try:
            proc = subprocess.Popen([sys.executable, "-c",
                                     "from sim._forkserver import warm_up; warm_up()"],
                                    cwd=ROOT, stdin=subprocess.DEVNULL,
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                    pass_fds=(held.fileno(),))
        except OSError:
            return None
    os.environ[WARMING] = str(lock)
    return proc


def wait_for_warm_up(path: str, timeout: float = WARM_WAIT_S) -> bool:
    """Wait until the warm-up holding the lock ``path`` has exited; False after ``timeout``
    s, or where the lock cannot be read."""
    deadline = time.monotonic() + timeout
    try:
        with open(path) as lock:
            while True:
                try:
                    fcntl.flock(lock, fcntl.LOCK_SH | fcntl.LOCK_NB)
                    return True
                except BlockingIOError:
                    if time.monotonic() >= deadline:
                        return False
                    time.sleep(0.1)
    except OSError:
        return False


def shared_fixture_group(item: pytest.Item) -> str | None:
    """The xdist group of a test that uses one of the suite's own shared fixtures (session
    scope: the fixture's name; module scope: the module), None for one that uses none.

    With ``--dist loadgroup`` the tests of one group run on one worker, so a shared
    fixture (a flight, a wheel, 150 configs analysed) is built once, not on every worker
    that happens to run one of its tests. The suite's own: defined in a module of
    ``tests`` (any folder's conftest or test module), not by pytest or a plugin.
    """
    info = getattr(item, "_fixtureinfo", None)
    if info is None:
        return None
    shared: dict[str, list[str]] = {"session": [], "module": []}
    for name in item.fixturenames:  # type: ignore[attr-defined]
        for fixturedef in info.name2fixturedefs.get(name, ()):
            module = getattr(fixturedef.func, "__module__", "")
            if module.split(".")[0] == "tests" and fixturedef.scope in shared:
                shared[fixturedef.scope].append(name)
    if shared["session"]:
        return f"fixture-{sorted(shared['session'])[0]}"
    if shared["module"]:
        return f"module-{item.module.__name__}"  # type: ignore[attr-defined]
    return None


def scheduled_first(item: pytest.Item) -> bool:
    """Whether a test goes to a worker before the rest: a long one (marker ``long``) or one
    of a group (the groups are the largest units of work the workers cannot split), so
    that none of them starts last and ends the run alone."""
    return (item.get_closest_marker("long") is not None
            or item.get_closest_marker("xdist_group") is not None)
