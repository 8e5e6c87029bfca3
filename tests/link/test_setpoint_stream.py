"""A team's setpoint stream (gcs.link._setpoint_stream) over real links to scripted ArduPilot
and PX4 peers: one call sends every vehicle its frame; what cannot be sent is named, never
raised; gaps between rounds are measured on the loop's clock; re-sends keep a slot."""

from __future__ import annotations

import math
import threading
import time
from typing import Any

import numpy as np

from gcs.link import SetpointStream
from tests.support.scripted_autopilot import Bench, peer_team

PEERS = {1: ("ardupilot", {}), 2: ("px4", {}), 3: ("ardupilot", {}), 4: ("px4", {})}


def _stream(bench: Bench, clock: list[float]) -> tuple[SetpointStream, list[tuple[int, str]]]:
    unsent: list[tuple[int, str]] = []
    profiles = [bench.manager.profiles[vid] for vid in (1, 2, 3, 4)]
    return SetpointStream(profiles, clock=lambda: clock[0], gap_s=0.3,
                          on_unsent=lambda vid, why: unsent.append((vid, why))), unsent


def _setpoints(bench: Bench, vid: int) -> list[Any]:
    return [r.msg for r in bench.peers[vid].setpoints()]


def test_one_round_reaches_every_vehicle_in_its_own_vertical_channel() -> None:
    with peer_team(PEERS) as bench:
        stream, unsent = _stream(bench, [0.0])
        stream.send(np.array([[0.1, 0.2], [0.3, 0.4], [0.5, 0.6], [0.7, 0.8]]),
                    np.full(4, -2.0))
        time.sleep(0.3)
        assert not unsent
        for vid in (1, 2, 3, 4):
            got = _setpoints(bench, vid)
            assert len(got) == 1, vid
            assert math.isclose(got[0].afx, 0.1 + 0.2 * (vid - 1), rel_tol=1e-6)
            assert got[0].target_system == vid


def test_what_cannot_be_sent_is_named_per_vehicle_and_the_rest_goes() -> None:
    with peer_team(PEERS) as bench:
        stream, unsent = _stream(bench, [0.0])
        stream.send(np.zeros((4, 2)), np.array([-2.0, math.nan, -2.0, math.inf]))
        time.sleep(0.3)
        assert unsent == [(2, "altitude target not finite: nan"),
                          (4, "altitude target not finite: inf")]
        assert [len(_setpoints(bench, vid)) for vid in (1, 2, 3, 4)] == [1, 0, 1, 0]
        unsent.clear()
        stream.send(np.zeros((4, 2)), np.full(4, math.nan))
        assert [vid for vid, _ in unsent] == [1, 2, 3, 4]


def test_a_gap_between_rounds_is_measured_on_the_loops_clock_and_a_stop_is_none() -> None:
    with peer_team(PEERS) as bench:
        clock = [10.0]
        stream, _ = _stream(bench, clock)
        for t in (10.0, 10.25, 10.5):
            clock[0] = t
            stream.send(np.zeros((4, 2)), np.full(4, -2.0))
        assert not stream.take_gap() and stream.gap_max == 0.25
        clock[0] = 11.0
        stream.send(np.zeros((4, 2)), np.full(4, -2.0))
        assert stream.take_gap() and not stream.take_gap() and stream.gap_max == 0.5
        stream.stop()
        assert stream.last_round == -math.inf
        clock[0] = 20.0
        stream.send(np.zeros((4, 2)), np.full(4, -2.0))  # a new stream: no gap
        assert not stream.take_gap() and stream.gap_max == 0.5


def test_re_sends_fill_the_slots_between_rounds_until_stopped() -> None:
    with peer_team(PEERS) as bench:
        stream, _ = _stream(bench, [0.0])
        fresh = (np.zeros((4, 2)), np.full(4, -2.0))
        done, stop = threading.Event(), threading.Event()
        errors: list[Exception | None] = []
        keeper = threading.Thread(target=stream.resend_while, args=(lambda: fresh,),
                                  kwargs={"slot": 0.05, "done": done, "stop": stop,
                                          "on_error": errors.append})
        keeper.start()
        time.sleep(0.5)
        stop.set()
        keeper.join(timeout=2.0)
        assert not keeper.is_alive()
        assert 5 <= stream.resends <= 11, stream.resends
        assert errors and all(e is None for e in errors)
