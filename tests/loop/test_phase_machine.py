"""The phase as state (gcs.loop._phase_machine): each change announced once; the abort's
hold started once, however many aborts arrive, and from any thread."""

from __future__ import annotations

import threading

import pytest

from gcs.loop import Action, Phase, PhaseError
from gcs.loop._events import EventLog
from gcs.loop._phase_machine import PhaseMachine


def _machine() -> tuple[PhaseMachine, EventLog]:
    log = EventLog(lambda: 7.0, None)
    return PhaseMachine(log), log


def test_each_phase_change_is_announced_once() -> None:
    phases, log = _machine()
    assert phases.phase is Phase.CONNECT
    phases.set(Phase.READY)
    phases.set(Phase.READY)
    phases.set(Phase.ARMED)
    assert [e.text for e in log.recent()] == ["phase: ready", "phase: armed"]


def test_an_action_goes_where_the_phase_table_says_or_is_refused() -> None:
    phases, _ = _machine()
    phases.set(Phase.HOVER)
    assert phases.target(Action.LIFT) is Phase.LIFTING
    with pytest.raises(PhaseError, match="cannot arm while hover"):
        phases.target(Action.ARM)


def test_aborts_from_many_threads_start_one_hold() -> None:
    phases, log = _machine()
    assert not log.recent()
    phases.set(Phase.FORMATION)
    started: list[Phase | None] = []
    threads = [threading.Thread(target=lambda: started.append(phases.start_abort(5.0)))
               for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert started.count(Phase.ABORTING) == 1 and started.count(None) == 7
    assert phases.phase is Phase.ABORTING and phases.abort_at == 5.0
    assert phases.start_abort(6.0) is None and phases.abort_at == 5.0  # not restarted
    assert [e.text for e in log.recent()] == ["phase: formation"]  # the caller announces


def test_no_abort_before_the_team_flies() -> None:
    phases, _ = _machine()
    phases.set(Phase.READY)
    with pytest.raises(PhaseError):
        phases.start_abort(1.0)
    assert phases.phase is Phase.READY and phases.abort_at is None
