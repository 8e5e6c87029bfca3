"""The suite's own scheduling: tests sharing a fixture run on one worker (tests/conftest.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import schedule_rank


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


def test_the_live_demo_then_the_grouped_and_long_tests_are_scheduled_before_the_rest(
        request: pytest.FixtureRequest) -> None:
    """In the session's order, the live demo's tests come first (where collected), then
    every grouped or long test, then the rest (in this file the first test has no group,
    the second has)."""
    ranks = [schedule_rank(item) for item in request.session.items]
    assert {1, 2} <= set(ranks)
    assert ranks == sorted(ranks), "a test comes before one that should start earlier"
    live = [item.name for item in request.session.items if schedule_rank(item) == 0]
    assert all(item.get_closest_marker("live_demo") for item in request.session.items[:len(live)])
