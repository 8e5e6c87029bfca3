"""Modes, commands with their acknowledgements, and the failsafes of the onboard autopilot."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from gcs.wire import SetpointKind, SimMode
from sim import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    build_team,
    load_world_config,
    paper_square,
    take_off,
)
from tests.support.worlds import solo
from vehicles import load_airframe, load_autopilot_config
from vehicles._outcomes import Denial, RequestOutcome


def denied(reason: Denial) -> RequestOutcome:
    return RequestOutcome(False, reason)


def test_modes_and_results_read_as_text() -> None:
    texts = {m.text for m in SimMode} | {k.text for k in SetpointKind}
    assert len(texts) == len(SimMode) + len(SetpointKind) and all(texts)
    assert RequestOutcome(True).text == "accepted"
    assert denied(Denial.DISARMED).text == "denied: vehicle is disarmed"
    with pytest.raises(ValueError):
        RequestOutcome(False)


def test_commands_are_acknowledged_or_denied_with_a_reason() -> None:
    world, autopilot = solo()
    assert autopilot.arm(0) == denied(Denial.NO_POSE)  # nothing measured yet
    world.run(autopilot, 0.125)
    assert autopilot.mode(0) == SimMode.DISARMED and not autopilot.armed[0]
    for command in (lambda: autopilot.takeoff(0, 1.0), lambda: autopilot.land(0),
                    lambda: autopilot.hold(0), lambda: autopilot.start_offboard(0)):
        assert command() == denied(Denial.DISARMED)
    assert autopilot.disarm(0).accepted  # already disarmed

    assert autopilot.arm(0).accepted
    assert autopilot.mode(0) == SimMode.HOLD and autopilot.armed[0]
    assert autopilot.arm(0).accepted  # already armed
    world.run(autopilot, 1.0)
    assert world.p_ned[0, 2] == pytest.approx(0.0, abs=0.002)  # idling on the ground
    assert np.all(world.rotor_speed[0] > 0.0)
    assert autopilot.start_offboard(0) == denied(Denial.NO_SETPOINT_STREAM)
    assert autopilot.takeoff(0, 0.01) == denied(Denial.BAD_ALTITUDE)
    assert autopilot.takeoff(0, math.nan) == denied(Denial.BAD_ALTITUDE)

    assert autopilot.takeoff(0, 1.2).accepted
    assert autopilot.mode(0) == SimMode.TAKEOFF
    world.run(autopilot, 6.0)
    assert autopilot.mode(0) == SimMode.HOLD
    assert -world.p_ned[0, 2] == pytest.approx(1.2, abs=0.05)
    assert autopilot.disarm(0) == denied(Denial.IN_FLIGHT)

    autopilot.set_accel_xy_pos_z_setpoint(0, (0.0, 0.0), -1.2)
    assert autopilot.start_offboard(0).accepted
    assert autopilot.mode(0) == SimMode.OFFBOARD

    assert autopilot.disarm(0, force=True).accepted  # kill switch
    world.run(autopilot, 1.0)
    assert autopilot.mode(0) == SimMode.DISARMED
    assert np.all(world.rotor_speed[0] < 1.0)
    assert world.p_ned[0, 2] == pytest.approx(0.0, abs=0.01)  # fell down


def test_land_descends_and_disarms_on_touchdown() -> None:
    world, autopilot = solo()
    take_off(world, autopilot, 1.0)
    assert autopilot.land(0).accepted
    heights, modes = [], []
    for _ in range(8 * 16):
        world.run(autopilot, 1.0 / 16.0)
        heights.append(-world.p_ned[0, 2])
        modes.append(autopilot.mode(0))
    descent = np.diff(heights[16:33]) * 16.0  # 1 to 2 s after the command
    assert descent.mean() == pytest.approx(-autopilot.config.land_speed, abs=0.1)
    assert modes[-1] == SimMode.DISARMED
    first_disarmed = modes.index(SimMode.DISARMED)
    assert all(m == SimMode.LAND for m in modes[:first_disarmed])
    assert heights[first_disarmed] < 0.01


def test_hold_lands_after_the_hold_timeout() -> None:
    config = dataclasses.replace(load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG),
                                 hold_timeout=2.0)
    world, autopilot = solo(config)
    take_off(world, autopilot, 1.0)
    hold_start = float(autopilot.state.hold_start[0])
    period = 1.0 / autopilot.rate_hz
    while autopilot.mode(0) == SimMode.HOLD:
        world.run(autopilot, period)
    assert autopilot.mode(0) == SimMode.LAND
    assert autopilot.t - hold_start == pytest.approx(2.0, abs=2 * period)
    world.run(autopilot, 6.0)
    assert autopilot.mode(0) == SimMode.DISARMED


def test_lost_setpoint_stream_switches_to_hold_after_half_a_second() -> None:
    airframe = load_airframe(DEFAULT_AIRFRAME)
    world, autopilot = build_team(paper_square(), payload_mass=0.4,
                                  rng=np.random.default_rng(12), airframe=airframe,
                                  world_config=load_world_config(DEFAULT_WORLD_CONFIG),
                                  autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    take_off(world, autopilot, 1.5)
    z_hold = autopilot.state.p_hold[:, 2].copy()
    period = 1.0 / autopilot.rate_hz
    lost = 2

    def stream(vehicles: range | list[int]) -> None:
        for i in vehicles:
            autopilot.set_accel_xy_pos_z_setpoint(i, (0.0, 0.0), z_hold[i])

    stream(range(4))
    for i in range(4):
        assert autopilot.start_offboard(i).accepted
    for _ in range(8):  # 2 s of the GCS's 4 Hz stream
        world.run(autopilot, 0.25)
        stream(range(4))
    last_setpoint = autopilot.t
    switched = None
    while autopilot.t - last_setpoint < 3.0:
        world.run(autopilot, period)
        if round((autopilot.t - last_setpoint) / period) % 128 == 0:  # others keep 4 Hz
            stream([i for i in range(4) if i != lost])
        if switched is None and autopilot.mode(lost) == SimMode.HOLD:
            switched = autopilot.t
            hold_point = autopilot.p_ned[lost]
    assert switched is not None
    assert 0.5 < switched - last_setpoint <= 0.5 + 1.5 * period
    assert [m.name for m in autopilot.modes] == ["OFFBOARD", "OFFBOARD", "HOLD", "OFFBOARD"]
    # 2.5 s later it still holds the point where the hold began.
    assert np.linalg.norm(world.p_ned[lost] - hold_point) < 0.05
