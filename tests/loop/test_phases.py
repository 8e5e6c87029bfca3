"""Phase transitions: the actions each phase takes, and why the others are refused."""

from __future__ import annotations

import pytest

from gcs.loop import Action, Phase, PhaseError
from gcs.loop._phases import next_phase


def test_normal_flight_sequence() -> None:
    phase = Phase.READY
    for action, want in ((Action.ARM, Phase.ARMED), (Action.TAKEOFF, Phase.TAKING_OFF)):
        phase = next_phase(phase, action)
        assert phase is want
    assert next_phase(Phase.HOVER, Action.LIFT) is Phase.LIFTING
    assert next_phase(Phase.FORMATION, Action.SET_DOWN) is Phase.SETTING_DOWN
    assert next_phase(Phase.HOVER, Action.LAND) is Phase.LANDING


def test_refused_actions_say_why() -> None:
    with pytest.raises(PhaseError, match="cannot lift while armed"):
        next_phase(Phase.ARMED, Action.LIFT)
    with pytest.raises(PhaseError, match="cannot take off while connect"):
        next_phase(Phase.CONNECT, Action.TAKEOFF)


def test_resume_keeps_the_phase_and_only_applies_while_streaming_in_flight() -> None:
    for phase in Phase:
        if phase in (Phase.HOVER, Phase.LIFTING, Phase.FORMATION, Phase.SETTING_DOWN):
            assert next_phase(phase, Action.RESUME) is phase
        else:
            with pytest.raises(PhaseError, match=f"cannot resume while {phase.text}"):
                next_phase(phase, Action.RESUME)


def test_abort_is_possible_whenever_something_can_fly() -> None:
    """It holds then lands from any phase but its own two: aborting and landing stay."""
    for phase in Phase:
        if phase in (Phase.CONNECT, Phase.READY, Phase.LANDED):
            with pytest.raises(PhaseError):
                next_phase(phase, Action.ABORT)
        elif phase in (Phase.ABORTING, Phase.LANDING):
            assert next_phase(phase, Action.ABORT) is phase
        else:
            assert next_phase(phase, Action.ABORT) is Phase.ABORTING
