"""The setpoint stream between guidance ticks, against the real simulator in real time.

Guidance runs at 4 Hz, but each vehicle gets ``guidance.setpoint_rate_hz``
(12 Hz) setpoints: the tick's own and re-sends of it. The vehicles' offboard
timeout is 0.5 s, so with one setpoint per tick a single tick 0.25 s late on
a busy machine was enough to send the whole team into hold (seen in CI).
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections import Counter
from collections.abc import Iterator

import numpy as np
import pytest

from gcs.app import GcsApp, SimProcess, free_tcp_port
from gcs.app._scenario import Scenario, Step, play
from gcs.config import load_team
from gcs.link._profile_sim import SimProfile
from gcs.loop import Phase
from gcs.transport import FrameDirection, ZenohSettings
from gcs.wire import SETPOINT_MESSAGE

TEAM = load_team("configs/bebop_square.yaml")


@contextlib.contextmanager
def hovering() -> Iterator[GcsApp]:
    """The real sim in real time and a GCS whose team has taken off and hovers."""
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    with SimProcess(TEAM.source, endpoint=endpoint, speed="1"), \
            GcsApp(TEAM, zenoh_settings=ZenohSettings(connect=(endpoint,))) as app:
        app.start()
        play(Scenario(name="up", steps=(Step(action="arm"), Step(action="takeoff"))),
             app.runtime, app.clock)
        assert app.runtime.phase is Phase.HOVER
        yield app


def test_each_tick_is_followed_by_resends_and_the_vehicles_stay_offboard() -> None:
    per_tick = TEAM.config.guidance.setpoints_per_tick
    assert per_tick == 3
    with hovering() as app:
        rt = app.runtime
        sent: Counter[int] = Counter()
        counting = threading.Event()

        def count(vid: int, direction: FrameDirection, frame: bytes) -> None:
            if counting.is_set() and direction is FrameDirection.OUT \
                    and int.from_bytes(frame[7:10], "little") == SETPOINT_MESSAGE.id:
                sent[vid] += 1

        for vid, link in app.links.links.items():
            link.add_frame_listener(lambda d, f, vid=vid: count(vid, d, f))
        ticks0, resends0 = rt.stats().ticks, rt.resends
        counting.set()
        time.sleep(2.0)
        counting.clear()
        ticks, resends = rt.stats().ticks - ticks0, rt.resends - resends0

        assert ticks >= 4, f"{ticks} ticks in 2 s"
        # every tick is followed by per_tick - 1 re-sends (give or take the window's edges)
        assert abs(resends - (per_tick - 1) * ticks) <= per_tick, (ticks, resends)
        for vid in TEAM.formation.ids:
            assert abs(sent[vid] - (ticks + resends)) <= 1, (vid, sent, ticks, resends)
        assert app.snapshot is not None
        assert set(app.snapshot.fleet.modes) == {"OFFBOARD"}, app.snapshot.fleet.modes


def test_lockstep_runs_send_one_setpoint_per_tick() -> None:
    """Re-sends would reach a lockstep sim at times that vary from run to run."""
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    with SimProcess(TEAM.source, endpoint=endpoint, speed="max", lockstep=True), \
            GcsApp(TEAM, zenoh_settings=ZenohSettings(connect=(endpoint,)), sim_clock=True,
                   lockstep=True) as app:
        assert app.runtime.setpoints_per_tick == 1
        app.start()
        play(Scenario(name="up", steps=(Step(action="arm"), Step(action="takeoff"))),
             app.runtime, app.clock)
        assert app.runtime.phase is Phase.HOVER
        app.clock.sleep_until(app.clock.now() + 1.0)
        assert app.runtime.resends == 0


def test_a_vehicle_whose_setpoint_cannot_be_sent_is_named_and_the_others_keep_theirs() -> None:
    """The fleet's setpoints are packed together; one failing link costs only its own."""
    with hovering() as app:
        rt = app.runtime
        sent: Counter[int] = Counter()
        for vid, link in app.links.links.items():
            link.add_frame_listener(
                lambda d, f, vid=vid: sent.update([vid]) if d is FrameDirection.OUT and
                int.from_bytes(f[7:10], "little") == SETPOINT_MESSAGE.id else None)
        app.links.links[3].close()  # its transport is gone: every send to it fails
        time.sleep(0.2)  # a round already under way as it closed may still have gone out
        before = Counter(sent)
        time.sleep(1.0)
        after = sent - before
        assert after[3] == 0, (before, sent)
        assert all(after[vid] >= 8 for vid in (1, 2, 4)), after  # 12 Hz for a second
        texts = [e.text for e in rt.events() if "setpoint not sent" in e.text]
        assert texts == ["vehicle 3: setpoint not sent: link is closed"], texts


def test_a_vehicle_whose_vertical_channel_fails_is_named_and_the_others_keep_theirs(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Profiles that compute their vertical channel (ArduPilot's GCS-side altitude loop) are
    asked per vehicle; one that raises or gives NaN costs only its own setpoint."""
    failing: dict[int, str] = {}

    def vertical_setpoint(self: SimProfile, z_ned: float) -> float:
        how = failing.get(self.link.sysid)
        if how == "raise":
            raise ValueError("no fresh position")
        return math.nan if how == "nan" else z_ned

    monkeypatch.setattr(SimProfile, "vertical_is_z", False)
    monkeypatch.setattr(SimProfile, "vertical_setpoint", vertical_setpoint)
    with hovering() as app:
        sent: Counter[int] = Counter()
        for vid, link in app.links.links.items():
            link.add_frame_listener(
                lambda d, f, vid=vid: sent.update([vid]) if d is FrameDirection.OUT and
                int.from_bytes(f[7:10], "little") == SETPOINT_MESSAGE.id else None)
        failing.update({2: "raise", 3: "nan"})
        time.sleep(0.3)  # a setpoint may have been on its way
        sent.clear()
        time.sleep(1.0)
        assert sent[2] == sent[3] == 0, sent
        assert sent[1] >= 8 and sent[4] >= 8, sent  # 12 Hz for a second
        texts = [e.text for e in app.runtime.events() if "setpoint not sent" in e.text]
        assert texts == ["vehicle 2: setpoint not sent: no fresh position",
                         "vehicle 3: setpoint not sent: vertical setpoint not finite: nan"], texts
        failing.clear()
        time.sleep(0.5)
        assert sent[2] >= 3 and sent[3] >= 3, sent
        # A non-finite altitude target reaches no vehicle, whatever its vertical channel
        # (2 and 3 are not named again: their warning above stands, one per vehicle).
        app.runtime.stages.setpoints.stream.send(np.zeros((4, 2)), np.full(4, math.nan))
        texts = [e.text for e in app.runtime.events() if "altitude target" in e.text]
        assert texts == ["vehicle 1: setpoint not sent: altitude target not finite: nan",
                         "vehicle 4: setpoint not sent: altitude target not finite: nan"], texts


def test_vehicles_in_offboard_get_setpoints_while_a_slow_one_is_still_switching() -> None:
    """The loop streams from the start of the offboard handover, not after the last switch.

    Vehicle 4's switch takes 1.2 s (a slow autopilot, or a loaded machine); the
    others, offboard already, would hold after 0.5 s without setpoints.
    """
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    with SimProcess(TEAM.source, endpoint=endpoint, speed="1"), \
            GcsApp(TEAM, zenoh_settings=ZenohSettings(connect=(endpoint,))) as app:
        slow = app.runtime.profiles[4]
        switch = slow.start_offboard

        def slow_switch(*, z_ned: float | None = None) -> None:
            time.sleep(1.2)
            switch(z_ned=z_ned)

        slow.start_offboard = slow_switch  # type: ignore[method-assign]
        app.start()
        play(Scenario(name="up", steps=(Step(action="arm"), Step(action="takeoff"))),
             app.runtime, app.clock)
        assert app.runtime.phase is Phase.HOVER
        time.sleep(0.3)
        assert set(app.snapshot.fleet.modes) == {"OFFBOARD"}, app.snapshot.fleet.modes
        dropped = [e.text for e in app.runtime.events() if "(was OFFBOARD)" in e.text]
        assert dropped == [], dropped
