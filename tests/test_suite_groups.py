"""The suite's own scheduling (tests/conftest.py, tests/support/scheduling.py): tests sharing a
fixture run on one worker, the long ones first, after the simulator's kernels are warm, the
test modules of every folder rewritten once."""

from __future__ import annotations

import fcntl
import os
from pathlib import Path
from types import SimpleNamespace

import pytest

from tests.support.paths import ROOT
from tests.support.scheduling import (
    WARMING,
    cache_rewritten,
    scheduled_first,
    suite_modules,
    wait_for_warm_up,
    warm_kernels,
)


@pytest.fixture(scope="module")
def shared() -> int:
    """A module-scoped fixture of the suite's own, as a flight or a built wheel would be."""
    return 1


def test_a_test_using_only_pytests_own_fixtures_is_scheduled_alone(
        request: pytest.FixtureRequest, tmp_path: Path) -> None:
    assert request.node.get_closest_marker("xdist_group") is None


def test_a_test_using_a_shared_module_fixture_runs_in_its_modules_group(
        request: pytest.FixtureRequest, shared: int) -> None:
    mark = request.node.get_closest_marker("xdist_group")
    assert mark is not None and mark.args == ("module-tests.test_suite_groups",), mark


def test_the_grouped_and_the_long_tests_are_scheduled_before_the_rest(
        request: pytest.FixtureRequest) -> None:
    """In the session's order, every grouped or long test comes before every other one (in
    this file the first test has no group, the second has)."""
    firsts = [scheduled_first(item) for item in request.session.items]
    assert any(firsts) and not all(firsts)
    assert firsts == sorted(firsts, reverse=True), "a grouped or long test comes late"


def test_the_kernels_warm_up_holds_the_workers_until_it_exits(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """With ``-n`` the controller starts the simulator's warm-up and the workers wait for
    it before their first test: the lock it holds is free only once it has exited."""
    monkeypatch.delenv("PYTEST_XDIST_WORKER", raising=False)  # as in the controller
    monkeypatch.delenv(WARMING, raising=False)
    config = SimpleNamespace(getoption=lambda name, default=None: 2)
    warm_up = warm_kernels(config, str(tmp_path))  # type: ignore[arg-type]
    assert warm_up is not None
    try:
        lock = os.environ[WARMING]
        # held while the warm-up runs (about 1 s, loading the cache)
        with open(lock) as held, pytest.raises(BlockingIOError):
            fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        assert wait_for_warm_up(lock, timeout=300.0)
        with open(lock) as free:
            fcntl.flock(free, fcntl.LOCK_EX | fcntl.LOCK_NB)  # nobody holds it any more
        assert warm_up.wait(5) == 0  # it exited, having loaded the kernels
    finally:
        if warm_up.poll() is None:
            warm_up.kill()
        warm_up.wait()


def test_the_rewritten_test_modules_are_cached_for_the_workers(
        pytestconfig: pytest.Config, tmp_path: Path) -> None:
    """Where Python may not write bytecode, pytest still reads its cache of a rewritten
    module: written once by the controller, the workers load it instead of rewriting."""
    from _pytest.assertion import rewrite

    module = tmp_path / "test_cached.py"
    module.write_text("def check(x):\n    assert x == 2\n")
    cache_rewritten(pytestconfig, [module])
    pyc = rewrite.get_cache_dir(module) / ("test_cached" + rewrite.PYC_TAIL)
    code = rewrite._read_pyc(module, pyc, lambda *_: None)
    assert code is not None, f"no cached rewritten module at {pyc}"
    namespace: dict[str, object] = {}
    exec(code, namespace)
    with pytest.raises(AssertionError, match="assert 1 == 2"):  # rewritten: it says why
        namespace["check"](1)  # type: ignore[operator]


def test_the_modules_rewritten_once_are_those_of_every_folder(
        request: pytest.FixtureRequest) -> None:
    """The controller rewrites the conftest files, the helpers and the test modules of every
    folder of tests/ (it globbed tests/test_*.py alone before the tests had folders): each
    folder has some, and every module this session collected is among them."""
    modules = set(suite_modules())
    folders = {p.parent for p in (ROOT / "tests").rglob("__init__.py")}
    assert {m.parent for m in modules} == folders
    assert ROOT / "tests" / "support" / "paths.py" in modules
    collected = {Path(str(item.path)) for item in request.session.items}
    assert collected <= modules, sorted(map(str, collected - modules))
