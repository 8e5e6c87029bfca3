"""What several test files share: the ``gcs`` command line, one recorded short flight, the
project's wheel installed in a venv, a second host, and how the suite is scheduled."""

from __future__ import annotations

import compileall
import contextlib
import fcntl
import io
import json
import os
import shutil
import signal
import site
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from gcs.testing import Host, NetnsUnavailableError

SQUARE = "configs/bebop_square.yaml"
SHORT = "configs/scenarios/short_flight.yaml"
ROOT = Path(__file__).resolve().parents[1]
SHIPPED = Path("share") / "formation-gcs" / "configs"
"""Where the wheel puts the configs it ships, under its environment's prefix."""

_CONFIG_HOMES: list[str] = []
_WARM_UPS: list[subprocess.Popen[bytes]] = []


PACKAGES = ("gcs", "sim", "vehicles", "web")
"""The project's packages, which the processes the suite starts import."""


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
    cache_rewritten(config, [ROOT / "tests" / "conftest.py",
                             *sorted((ROOT / "tests").glob("test_*.py"))])


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
    s of CPU each), and wait for it before their first test (:func:`pytest_runtest_setup`).
    Loaded from the cache, about 1 s. A failure here only leaves each process to compile
    what it needs. Returns the warm-up's process (None: not started)."""
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


_warm = False


def pytest_runtest_setup(item: pytest.Item) -> None:
    """A worker's first test waits for the kernels' warm-up (:func:`warm_kernels`)."""
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


def shared_fixture_group(item: pytest.Item) -> str | None:
    """The xdist group of a test that uses one of the suite's own shared fixtures (session
    scope: the fixture's name; module scope: the module), None for one that uses none.

    With ``--dist loadgroup`` the tests of one group run on one worker, so a shared
    fixture (a flight, a wheel, 150 configs analysed) is built once, not on every worker
    that happens to run one of its tests.
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


def run_gcs(*args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    """``python -m gcs ARGS`` in a subprocess, output captured, never raising on exit status."""
    return subprocess.run([sys.executable, "-m", "gcs", *args], capture_output=True, text=True,
                          timeout=timeout, check=False)


def gcs_here(*args: str) -> subprocess.CompletedProcess[str]:
    """``gcs ARGS`` run by the command line's own ``main`` in this process, its output and
    exit status captured as :func:`run_gcs` gives them.

    For tests of what a command computes and says (an analysis, a report, a refusal): a
    subprocess spent about a second of CPU starting Python and loading the kernels before
    it did anything, some sixty times a suite. Where the process is the subject (its exit,
    signals, what reaches a terminal), :func:`run_gcs`.
    """
    from gcs.cli import main

    out, err = io.StringIO(), io.StringIO()
    handlers = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(list(args))
            except SystemExit as exc:  # argparse's usage errors
                code = exc.code if isinstance(exc.code, int) else int(exc.code is not None)
    finally:
        for sig, handler in handlers.items():  # main() makes them raise KeyboardInterrupt
            if handler is not None:  # None: set outside Python, left as main() made it
                signal.signal(sig, handler)
    return subprocess.CompletedProcess(["gcs", *args], code, out.getvalue(), err.getvalue())


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


def run_outside(cmd: list[str], cwd: Path,
                timeout: float = 180) -> subprocess.CompletedProcess[str]:
    """``cmd`` in ``cwd`` without this checkout's PYTHONPATH or venv, output captured."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout, check=False)


@pytest.fixture(scope="session")
def installed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """(venv, an empty working directory) with the project's wheel installed in the venv:
    built once for the session (tests/test_install.py, tests/test_plugin_outside.py)."""
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
