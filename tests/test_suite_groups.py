"""The suite's own scheduling: tests sharing a fixture run on one worker (tests/conftest.py)."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(scope="module")
def shared() -> int:
    """A module-scoped fixture of the suite's own, as a flight or a built wheel would be."""
    return 1


def test_a_test_using_a_shared_module_fixture_runs_in_its_modules_group(
        request: pytest.FixtureRequest, shared: int) -> None:
    mark = request.node.get_closest_marker("xdist_group")
    assert mark is not None and mark.args == ("module-tests.test_suite_groups",), mark


def test_a_test_using_only_pytests_own_fixtures_is_scheduled_alone(
        request: pytest.FixtureRequest, tmp_path: Path) -> None:
    assert request.node.get_closest_marker("xdist_group") is None
