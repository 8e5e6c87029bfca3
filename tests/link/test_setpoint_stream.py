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


def _counts(bench: Bench, expected: list[int], timeout_s: float = 10.0) -> list[int]:
    """Each peer's count of setpoints once they reach ``expected`` (or the timeout passed),
    and a little longer, so that one more on its way would be counted too."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        counts = [len(_setpoints(bench, vid)) for vid in (1, 2, 3, 4)]
        if counts == expected:
            break
        time.sleep(0.02)
    time.sleep(0.1)
    return [len(_setpoints(bench, vid)) for vid in (1, 2, 3, 4)]


def test_one_round_reaches_every_vehicle_in_its_own_vertical_channel() -> None:
    with peer_team(PEERS) as bench:
        stream, unsent = _stream(bench, [0.0])
        stream.send(np.array([[0.1, 0.2], [0.3, 0.4], [0.5, 0.6], [0.7, 0.8]]),
                    np.full(4, -2.0))
        assert _counts(bench, [1, 1, 1, 1]) == [1, 1, 1, 1]
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
        assert unsent == [(2, "altitude target not finite: nan"),
                          (4, "altitude target not finite: inf")]
        assert _counts(bench, [1, 0, 1, 0]) == [1, 0, 1, 0]
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
        slot = 0.05
        keeper = threading.Thread(target=stream.resend_while, args=(lambda: fresh,),
                                  kwargs={"slot": slot, "done": done, "stop": stop,
                                          "on_error": errors.append})
        started = time.monotonic()
        keeper.start()
        time.sleep(0.5)
        stop.set()
        keeper.join(timeout=2.0)
        elapsed = time.monotonic() - started
        assert not keeper.is_alive()
        # at most one a slot (a busy machine gives fewer, never more), and some at all
        assert 1 <= stream.resends <= elapsed / slot + 1, (stream.resends, elapsed)
        assert len(errors) == stream.resends and all(e is None for e in errors)
        assert _counts(bench, [stream.resends] * 4) == [stream.resends] * 4


def test_exactly_the_vehicles_with_a_target_that_is_not_finite_are_left_out() -> None:
    """Over random rounds (seeded), each with random targets not finite: those vehicles are
    named with their value and get nothing; every other one gets its frame."""
    rng = np.random.default_rng(46)
    with peer_team(PEERS) as bench:
        stream, unsent = _stream(bench, [0.0])
        expected = [0, 0, 0, 0]
        for _ in range(12):
            targets = -rng.uniform(0.5, 3.0, 4)
            bad = rng.random(4) < 0.4
            targets[bad] = rng.choice([math.nan, math.inf, -math.inf], int(bad.sum()))
            unsent.clear()
            stream.send(rng.uniform(-1.0, 1.0, (4, 2)), targets)
            named = [(k + 1, f"altitude target not finite: {targets[k]}")
                     for k in np.flatnonzero(bad)]
            assert unsent == named, (targets, unsent)
            expected = [n + int(not b) for n, b in zip(expected, bad, strict=True)]
        assert _counts(bench, expected) == expected
