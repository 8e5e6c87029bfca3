"""A worker thread that does not stop when closed is named, not left running in silence."""

from __future__ import annotations

import logging
import threading

import pytest

from gcs.common import join_thread


def test_a_thread_that_outlives_its_join_is_reported(caplog: pytest.LogCaptureFixture) -> None:
    release = threading.Event()
    stuck = threading.Thread(target=release.wait, name="stuck-reader", daemon=True)
    stuck.start()
    with caplog.at_level(logging.WARNING, logger="gcs.common._threads"):
        assert join_thread(stuck, 0.05, what="the test's reader") is False
    assert [r.getMessage() for r in caplog.records] == [
        "the test's reader (thread 'stuck-reader') did not stop within 0.05 s; left running"]
    release.set()
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="gcs.common._threads"):
        assert join_thread(stuck, 2.0, what="the test's reader") is True
    assert not caplog.records


def test_no_thread_an_unstarted_one_or_the_caller_itself_is_fine() -> None:
    assert join_thread(None, 0.01, what="nothing")
    assert join_thread(threading.Thread(target=lambda: None), 0.01, what="never started")
    answers: list[bool] = []
    me = threading.Thread(target=lambda: answers.append(join_thread(me, 0.01, what="itself")))
    me.start()
    me.join(timeout=2.0)
    assert answers == [True]
