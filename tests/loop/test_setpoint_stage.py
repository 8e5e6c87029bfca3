"""The setpoint stage (gcs.loop._setpoint_stage) on a real loop over scripted ArduPilot
links: the altitude target under the ceiling, re-sends only while the phase streams, and a
re-send past its hold time damping velocity instead of the old tick's command."""

from __future__ import annotations

import time

import numpy as np

from gcs.loop import HELD_SETPOINT_S, Phase
from tests.support.scripted_autopilot import peer_team

ARDUPILOTS = {vid: ("ardupilot", {}) for vid in (1, 2, 3, 4)}


def test_a_tick_is_re_sent_while_the_phase_streams_then_damped_once_held_too_long() -> None:
    with peer_team(ARDUPILOTS) as bench:
        runtime = bench.runtime
        stage = runtime.stages.setpoints
        accel = np.full((4, 2), 0.3)
        runtime.phases.set(Phase.HOVER)
        op = runtime.operator.snapshot(runtime.clock.now())
        stage.send(runtime.clock.now(), accel, op)
        again = stage.refresh()
        assert again is not None
        assert again[0] is accel
        assert np.all(again[1] == -stage.altitude(op))  # no trims: one altitude for all
        stage.hold_back()  # a tick computing: nothing of the last one meanwhile
        assert stage.refresh() is None
        stage.send(runtime.clock.now(), accel, op)
        time.sleep(HELD_SETPOINT_S + 0.1)
        held = stage.refresh()
        assert held is not None and not np.any(held[0] == 0.3)
        assert np.all(np.abs(held[0]) < 0.3)  # the team is still: damping is about nothing
        runtime.phases.set(Phase.LANDED)
        assert stage.refresh() is None


def test_the_altitude_target_is_never_above_the_geofences_ceiling() -> None:
    with peer_team(ARDUPILOTS) as bench:
        stage, runtime = bench.runtime.stages.setpoints, bench.runtime
        ceiling = bench.team.config.safety.geofence_altitude
        runtime.operator.reset_altitude(ceiling + 5.0, now=runtime.clock.now())
        assert stage.altitude(runtime.operator.snapshot(runtime.clock.now())) == ceiling


def test_the_take_offs_handover_streams() -> None:
    with peer_team(ARDUPILOTS) as bench:
        runtime = bench.runtime
        stage = runtime.stages.setpoints
        assert not stage.streams(Phase.TAKING_OFF)
        runtime.actions.handing_over = True
        assert stage.streams(Phase.TAKING_OFF)
        assert all(stage.streams(p) for p in Phase if p.streaming)
