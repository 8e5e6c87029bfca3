"""The suite's own scheduling: tests sharing a fixture run on one worker (tests/conftest.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.conftest import scheduled_first


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
