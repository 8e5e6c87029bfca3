"""When vehicles that dropped out of their streaming mode are re-engaged (gcs.loop._recovery)."""

from __future__ import annotations

from gcs.loop._recovery import GAP_WINDOW_S, Recovery


def ticks(r: Recovery, start: float, end: float, *, out: tuple[int, ...],
          healthy: bool) -> list[float]:
    """The times, at 4 Hz from ``start`` to ``end``, at which ``r`` says to re-engage."""
    fired, t = [], start
    while t <= end + 1e-9:
        if r.update(t, out=out, healthy=healthy):
            fired.append(round(t, 2))
        t += 0.25
    return fired


def test_nothing_happens_while_the_team_is_not_healthy() -> None:
    r = Recovery(automatic=True, settle=1.0)
    r.note_gap(10.0)
    assert ticks(r, 10.25, 12.0, out=(2, 3), healthy=False) == []  # links still stale
    assert r.status(12.0) == "vehicles 2, 3 out of the streaming mode: waiting for every link"
    assert ticks(r, 12.25, 13.25, out=(2, 3), healthy=True) == [13.25]  # a whole settle later


def test_settle_then_one_try_per_settle_period() -> None:
    r = Recovery(automatic=True, settle=1.0)
    r.note_gap(10.0)
    assert ticks(r, 10.25, 13.0, out=(2, 3), healthy=True) == [11.25, 12.25]
    assert r.attempts == 2 and r.after_gap == (2, 3)
    assert r.status(12.5).startswith("vehicles 2, 3 out of the streaming mode: re-engaging in ")


def test_a_vehicle_that_left_its_mode_with_no_gap_waits_for_the_operator() -> None:
    r = Recovery(automatic=True, settle=1.0)
    r.note_gap(0.0)
    assert ticks(r, GAP_WINDOW_S + 1.0, GAP_WINDOW_S + 5.0, out=(4,), healthy=True) == []
    assert r.status(9.0) == "vehicles 4 out of the streaming mode: press Resume to fly them again"
    # back in its mode, then out again right after a gap: that one is the gap's
    assert not r.update(20.0, out=(), healthy=True)
    r.note_gap(20.5)
    assert ticks(r, 21.0, 22.0, out=(4,), healthy=True) == [22.0]


def test_the_operator_policy_never_re_engages_but_says_who_waits() -> None:
    r = Recovery(automatic=False, settle=1.0)
    r.note_gap(1.0)
    assert ticks(r, 1.25, 10.0, out=(1, 2, 3, 4), healthy=True) == []
    assert r.status(10.0) == ("vehicles 1, 2, 3, 4 out of the streaming mode: press Resume "
                              "to fly them again")
    assert not r.update(10.25, out=(), healthy=True) and r.status(10.25) == ""
