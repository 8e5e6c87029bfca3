"""Fuzzing the sim's control parser (``sim._faults.parse_control``), the zenoh control key.

Anyone on the fabric can publish on ``fleet/<fleet>/sim/control``; a message
of nested JSON killed the sim (RecursionError out of the parser). Whatever
the bytes, the parser returns a command or raises ValueError, quickly and
silently. ``bench/fuzz.py --only sim_control`` runs 10^6 inputs.
"""

from __future__ import annotations

from collections import Counter

import pytest
from hypothesis import given
from hypothesis import strategies as st

from sim._faults import CONTROL_MAX_BYTES, ControlAction, ControlCommand, parse_control
from tests.support.fuzzing import (
    assert_quiet,
    batches,
    fuzz_settings,
    hostile_json,
    json_values,
    mutate,
    mutations,
    timed,
    to_json,
)

commands = st.builds(lambda action, sysid: ControlCommand(action, sysid).to_bytes(),
                     st.sampled_from(list(ControlAction)), st.integers(-300, 300))
objects = st.builds(lambda action, sysid, extra: to_json(
    {"action": action, "sysid": sysid} | ({} if extra is None else {"extra": extra})),
    json_values | st.sampled_from(["kill", "cut"]), json_values | st.integers(0, 256),
    st.none() | json_values)
control_inputs = (st.binary(max_size=2 * CONTROL_MAX_BYTES) | json_values.map(to_json)
                  | hostile_json | commands | st.builds(mutate, commands, mutations) | objects)


def test_the_control_parser_returns_a_command_or_refuses_with_a_value_error(
        capfd: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture) -> None:
    outcomes: Counter[str] = Counter()

    @fuzz_settings(1000)
    @given(batches(control_inputs))
    def fuzz(inputs: list[bytes]) -> None:
        for data in inputs:
            with timed():
                try:
                    command = parse_control(data)
                except ValueError as exc:
                    outcomes["refused"] += 1
                    assert str(exc)
                    continue
            outcomes["accepted"] += 1
            assert len(data) <= CONTROL_MAX_BYTES
            assert isinstance(command.action, ControlAction) and isinstance(command.sysid, int)

    fuzz()
    assert_quiet(capfd, caplog)
    assert sum(outcomes.values()) == 10_000
    assert outcomes["accepted"] > 500 and outcomes["refused"] > 3000, outcomes
