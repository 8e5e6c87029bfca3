"""The event log (gcs.loop._events): each condition said once while it lasts, errors counted
past the recent list, every event recorded at its MAVLink severity."""

from __future__ import annotations

import numpy as np
import pytest

from gcs.loop._events import EventLog


class _Texts:
    """A flight recorder that keeps the texts only."""

    def __init__(self) -> None:
        self.said: list[tuple[float, str, int]] = []

    def text(self, t: float, text: str, *, severity: int) -> None:
        self.said.append((t, text, severity))

    def frame(self, t: float, frame: bytes) -> None:
        raise AssertionError("the event log records no frames")

    def team(self, t: float, *, ids: tuple[int, ...], edges: np.ndarray,
             distances: np.ndarray, accel_norm: float, accel_axis: float) -> None:
        raise AssertionError("the event log records no team")

    def internals(self, t: float, *, arrays: dict[str, np.ndarray],
                  sticks: tuple[float, float, float], scale: float, altitude: float,
                  phase: int) -> None:
        raise AssertionError("the event log records no internals")


def test_a_condition_is_said_once_while_it_lasts_and_again_after_it_cleared() -> None:
    log = EventLog(lambda: 1.0, None)
    for _ in range(5):
        log.warn_once(("send", 3), "vehicle 3: setpoint not sent")
    log.warn_once(("send", 4), "vehicle 4: setpoint not sent")
    assert [e.text for e in log.recent()] == ["vehicle 3: setpoint not sent",
                                               "vehicle 4: setpoint not sent"]
    log.unlatch(("send", 3))
    log.warn_once(("send", 3), "vehicle 3: setpoint not sent")
    log.warn_once(("send", 4), "vehicle 4: setpoint not sent")
    assert [e.text for e in log.recent()].count("vehicle 3: setpoint not sent") == 2
    assert [e.text for e in log.recent()].count("vehicle 4: setpoint not sent") == 1
    assert all(e.level == "warning" for e in log.recent())


def test_errors_are_counted_past_the_recent_events() -> None:
    log = EventLog(lambda: 2.0, None)
    for k in range(250):
        log.add("error" if k % 2 else "info", f"event {k}")
    recent = log.recent()
    assert len(recent) == 200 and recent[-1].text == "event 249" and recent[0].t == 2.0
    assert log.errors == 125


def test_a_note_from_outside_the_loop_names_a_wrong_level() -> None:
    log = EventLog(lambda: 0.0, None)
    with pytest.raises(ValueError, match="'loud'"):
        log.note("loud", "hello")
    log.note("info", "vehicle 2 appeared")
    assert [e.text for e in log.recent()] == ["vehicle 2 appeared"]


def test_every_event_is_recorded_at_its_mavlink_severity_and_time() -> None:
    times = iter((1.0, 2.0, 3.0))
    recorder = _Texts()
    log = EventLog(lambda: next(times), recorder)
    log.add("info", "phase: ready")
    log.add("warning", "loop stalled")
    log.add("error", "arm failed")
    assert recorder.said == [(1.0, "phase: ready", 6), (2.0, "loop stalled", 4),
                             (3.0, "arm failed", 3)]
