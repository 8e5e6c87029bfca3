"""The lockstep gate: helper threads act only inside a tick's window (real threads)."""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from gcs.loop import ClockStoppedError, ExternalClock, GatedClock, StepGate


def test_disabled_gate_gates_nothing() -> None:
    gate = StepGate(enabled=False)
    with gate.participant():
        assert gate.pause() is False  # the caller waits its own way
    assert gate.window() is True
    with ThreadPoolExecutor(2) as pool:
        assert gate.submit(pool, lambda: 7).result() == 7
        assert isinstance(gate.map(pool, lambda x: 1 / x, [1, 0])[1], ZeroDivisionError)


def test_a_participant_acts_once_per_window_and_the_window_waits_for_it() -> None:
    gate = StepGate(enabled=True)
    seen: list[int] = []
    window = [0]

    def act() -> None:
        for _ in range(3):
            time.sleep(0.02)  # slow work: the window must wait for it
            seen.append(window[0])
            gate.pause()

    with ThreadPoolExecutor(2) as pool:
        done = gate.submit(pool, act)
        assert gate.window()  # the first step ran before the first window
        for k in (1, 2, 3):
            window[0] = k
            assert gate.window()
            assert len(seen) == min(k + 1, 3)  # this window's step is in when it returns
        done.result(timeout=5)
    assert seen == [0, 1, 2]


def test_map_hands_the_count_back_so_no_window_closes_between_items_and_caller() -> None:
    gate = StepGate(enabled=True)
    log: list[str] = []
    window = [0]

    def item(k: int) -> None:
        for _ in range(k):  # item k waits k windows
            gate.pause()
        log.append(f"item {k} in window {window[0]}")

    def action() -> None:
        errors = gate.map(pool, item, [1, 2, 3])
        assert errors == [None, None, None]
        log.append(f"caller in window {window[0]}")

    with ThreadPoolExecutor(6) as pool:
        done = gate.submit(pool, action)
        assert gate.window()  # window 0: everything started and parked
        for k in range(1, 6):
            window[0] = k
            assert gate.window()
        done.result(timeout=5)
    assert log == ["item 1 in window 1", "item 2 in window 2", "item 3 in window 3",
                   "caller in window 3"]


def test_items_failing_are_reported_per_item() -> None:
    gate = StepGate(enabled=True)

    def item(x: int) -> None:
        gate.pause()
        if x == 2:
            raise ValueError("vehicle 2 refused")

    out: list[BaseException | None] = []
    with ThreadPoolExecutor(4) as pool:
        done = gate.submit(pool, lambda: out.extend(gate.map(pool, item, [1, 2, 3])))
        while not done.done():
            gate.window()
    assert [type(e).__name__ if e else None for e in out] == [None, "ValueError", None]


def test_a_busy_participant_is_waited_for_at_most_the_cap() -> None:
    gate = StepGate(enabled=True, hold_cap_s=0.1)
    release = threading.Event()
    with ThreadPoolExecutor(1) as pool:
        gate.submit(pool, release.wait, 5.0)
        t0 = time.monotonic()
        assert gate.window() is False
        assert time.monotonic() - t0 < 1.0
        release.set()


def test_close_releases_parked_participants_and_gating_stops() -> None:
    gate = StepGate(enabled=True)
    with ThreadPoolExecutor(1) as pool:
        parked = gate.submit(pool, lambda: (gate.pause(), gate.pause()))
        assert gate.window()  # it runs in the window, up to its first pause
        gate.close()
        assert parked.result(timeout=2) == (True, False)
        assert gate.window() is True


def test_work_submitted_between_windows_starts_only_in_the_next_window() -> None:
    # as the loop's tick submits a recovery's resume: started at once, it raced the rest
    # of the tick (its setpoint before or after the tick's), and runs of a seed differed
    gate = StepGate(enabled=True)
    started = threading.Event()
    with ThreadPoolExecutor(2) as pool:
        done = gate.submit(pool, started.set)
        assert not started.wait(0.2)
        assert gate.window()
        assert started.is_set()  # in the window, which waited for it
        done.result(timeout=2)
        late = gate.submit(pool, started.clear)  # parked when the gate closes: runs then
        gate.close()
        late.result(timeout=2)
    assert not started.is_set()


def test_gated_clock_wakes_a_participant_at_the_first_tick_at_or_after_the_time() -> None:
    clock = ExternalClock(timeout=2.0)
    gate = StepGate(enabled=True)
    woke: list[float] = []

    def scenario() -> None:
        GatedClock(clock, gate).sleep_until(0.6)
        woke.append(clock.now())

    with ThreadPoolExecutor(1) as pool:
        done = gate.submit(pool, scenario)
        for t in (0.25, 0.5, 0.75, 1.0):
            clock.advance(t)
            gate.window()
        done.result(timeout=2)
    assert woke == [0.75]


def test_an_external_clock_starts_at_its_first_sample() -> None:
    # the loop anchors its ticks after its first sleep: on the simulator's first time, not
    # on a 0.0 read before the first sample came (on one run and not another)
    clock = ExternalClock(timeout=2.0)
    threading.Timer(0.1, clock.advance, args=(1 / 128,)).start()
    clock.sleep_until(0.0)
    assert clock.now() == 1 / 128


def test_a_stopped_clock_is_timed_from_its_last_sample_and_tells_every_waiter_at_once() -> None:
    # the loop and the scenario behind it both wait on the simulator's clock: when it
    # stops, the second must not wait out a timeout of its own after the first gave up
    clock = ExternalClock(timeout=2.0)
    clock.advance(0.5)
    time.sleep(1.2)
    start = time.monotonic()
    with pytest.raises(ClockStoppedError, match=r"no simulator clock sample for 2 s \(stuck "
                                                r"at t = 0\.500 s\)"):
        clock.sleep_until(1.0)
    assert time.monotonic() - start < 1.6  # 2 s after the sample (0.8 s on), not the call
    start = time.monotonic()
    with pytest.raises(ClockStoppedError, match="no simulator clock sample for 2 s"):
        clock.sleep_until(1.0)
    assert time.monotonic() - start < 1.6  # at once (old: 2 s more): it stays stopped
    clock.advance(0.75)  # a late sample does not restart a clock the loop has given up on
    with pytest.raises(ClockStoppedError):
        clock.sleep_until(1.0)
