"""How the ticks kept time (gcs.loop._snapshot.TickTimer)."""

from __future__ import annotations

import pytest

from gcs.loop._snapshot import TickTimer


def test_no_tick_yet_reads_zeros() -> None:
    stats = TickTimer().stats(setpoint_gap_max=0.0)
    assert (stats.ticks, stats.compute_last, stats.jitter_p99, stats.overruns) == (0, 0, 0, 0)


def test_the_recent_ticks_percentiles_the_latest_stall_and_the_streams_gap() -> None:
    timer = TickTimer()
    for k in range(500):
        timer.started(0.001 if k != 450 else 0.6)
        timer.computed(0.002 if k != 499 else 0.004)
    timer.overruns += 1
    stats = timer.stats(setpoint_gap_max=0.26)
    assert stats.ticks == 500 and stats.compute_last == 0.004
    assert stats.compute_p99 == pytest.approx(0.002, abs=1e-3)
    assert stats.jitter_p99 == pytest.approx(0.001, abs=1e-2)
    assert stats.stall_max == 0.6 and stats.overruns == 1 and stats.setpoint_gap_max == 0.26
