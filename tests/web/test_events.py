"""The page's events as an operator reads them, and why four vehicles went stale at once.

Grouping is plain functions over events (``web._events``): one line per
condition with its count and vehicles, the log's bursts. The stale storm had a
cause in the simulator: its mode entries, called from Python at a command,
compiled at first use while the whole simulator stood still.
"""

from __future__ import annotations

import subprocess
import sys

from gcs.link import LinkHealth
from gcs.loop import Event
from tests.support.paths import ROOT
from web._events import EventLog, bursts, condition, conditions, split_vehicle
from web._link_quality import LinkQuality, received_share
from web._replay import ReplayEvent


def stale(t: float, vid: int, seconds: float) -> Event:
    return Event(t, "warning", f"vehicle {vid}: no fresh telemetry for {seconds:.2f} s: "
                               "motion frozen")


def storm(repeats: int) -> list[Event]:
    """Four vehicles stale at once, ``repeats`` times, with other events between."""
    out = []
    for k in range(repeats):
        t = 10.0 * k
        out += [stale(t, vid, 0.5 + 0.01 * vid) for vid in (1, 2, 3, 4)]
        out += [Event(t + 0.25, "warning", f"vehicle {vid}: mode HOLD (was OFFBOARD)")
                for vid in (4, 3, 2, 1)]
        out.append(Event(t + 3.0, "info", "recovery: every link fresh for 1 s: re-engaging "
                                          "vehicles 1, 2, 3, 4"))
    return out


def test_a_storm_of_four_vehicles_stale_is_one_condition_with_its_count() -> None:
    lines = conditions(storm(3))
    assert [line.describe() for line in lines] == [
        "mode HOLD (was OFFBOARD) ×12 — vehicles 1,2,3,4",
        "no fresh telemetry for 0.54 s: motion frozen ×12 — vehicles 1,2,3,4",
    ]
    assert (lines[1].first_t, lines[1].t, lines[1].level) == (0.0, 20.0, "warning")
    # the information lines are the log's, not the conditions'
    assert all("recovery" not in line.text for line in lines)
    assert [line.text for line in conditions(storm(1), levels=("info",))] == [
        "recovery: every link fresh for 1 s: re-engaging vehicles 1, 2, 3, 4"]


def test_the_log_keeps_time_order_with_each_burst_one_line() -> None:
    log = bursts(storm(2), window=1.0)
    assert [(line.first_t, line.describe()) for line in log] == [
        (0.0, "no fresh telemetry for 0.54 s: motion frozen ×4 — vehicles 1,2,3,4"),
        (0.25, "mode HOLD (was OFFBOARD) ×4 — vehicles 1,2,3,4"),
        (3.0, "recovery: every link fresh for 1 s: re-engaging vehicles 1, 2, 3, 4"),
        (10.0, "no fresh telemetry for 0.54 s: motion frozen ×4 — vehicles 1,2,3,4"),
        (10.25, "mode HOLD (was OFFBOARD) ×4 — vehicles 1,2,3,4"),
        (13.0, "recovery: every link fresh for 1 s: re-engaging vehicles 1, 2, 3, 4"),
    ]
    # a replayed flight: 44 texts of a 91 s flight (each phase change, four mode lines
    # each) read as a dozen lines
    modes = [("DISARMED", "unknown"), ("HOLD", "DISARMED"), ("TAKEOFF", "HOLD"),
             ("OFFBOARD", "TAKEOFF"), ("LAND", "OFFBOARD"), ("DISARMED", "LAND")]
    replayed = [ReplayEvent(float(k), "text", f"vehicle {vid}: mode {a} (was {b})")
                for k, (a, b) in enumerate(modes) for vid in (1, 2, 3, 4)]
    replayed += [ReplayEvent(k + 0.5, "phase", f"phase: {name}") for k, name in enumerate(
        ("ready", "armed", "taking off", "hover", "landing", "landed"))]
    replayed.sort(key=lambda e: e.t)
    assert len(replayed) == 30 and len(bursts(replayed)) == 12


def test_conditions_ignore_the_vehicle_and_the_numbers() -> None:
    assert split_vehicle("vehicle 12: in HOLD") == (12, "in HOLD")
    assert split_vehicle("2: rope snag") == (2, "rope snag")  # a vehicle's own text, replayed
    assert split_vehicle("vehicle 3 appeared (MAVLink heartbeat)") == (
        3, "vehicle appeared (MAVLink heartbeat)")
    assert split_vehicle("loop stalled: tick 0.61 s late") == (
        None, "loop stalled: tick 0.61 s late")
    assert condition("warning", "vehicle 1: no fresh telemetry for 0.52 s: motion frozen") == \
        condition("warning", "vehicle 4: no fresh telemetry for 1.7 s: motion frozen")
    assert condition("warning", "x") != condition("error", "x")
    assert condition("info", "phase: hover") != condition("info", "phase: lifting")


def test_the_event_log_keeps_what_the_loop_forgot() -> None:
    log = EventLog(keep=50)
    events = storm(1)
    assert log.take(tuple(events[:5])) and list(log.events) == events[:5]
    assert not log.take(tuple(events[:5]))  # nothing new
    recent = tuple(events[3:9])  # the loop's window moved on
    assert log.take(recent) and list(log.events) == events[:9]
    later = tuple(storm(2)[9:])  # the last one taken is gone from the loop's window
    assert log.take(later) and list(log.events)[9:] == list(later)


def test_link_quality_is_the_share_received_over_the_last_seconds() -> None:
    def health(received: int, lost: int, alive: bool = True) -> dict[int, LinkHealth]:
        return {1: LinkHealth(sysid=1, heartbeat_age_s=0.1, alive=alive,
                              frames_received=received, frames_sent=0, packets_lost=lost,
                              refused_bad_crc=0, refused_signature=0, refused_wrong_system=0,
                              foreign_systems=(), garbage_bytes=0, truncated=0, rtt_s=None)}

    assert received_share(90, 10) == 90.0
    quality = LinkQuality(window=5.0)
    assert quality.update(0.0, health(1000, 0)) == {1: 100.0}
    assert quality.update(1.0, health(1090, 10)) == {1: 90.0}  # this second: 90 of 100
    assert quality.update(7.0, health(1690, 10)) == {1: 100.0}  # the loss left the window
    assert quality.update(8.0, health(1690, 10, alive=False)) == {1: 0.0}
    # a frame counted lost before the window arrived late in it: counted back, never
    # more than all received
    assert quality.update(13.0, health(1790, 9)) == {1: 100.0}


def test_every_mode_entry_is_compiled_before_the_first_command() -> None:
    """The cause of the stale storm: the first arm, take-off, offboard and landing each
    compiled its mode entry while the simulator stood still (0.35-0.6 s each with a cold
    cache: every vehicle's telemetry aged to the 0.5 s stale bound at each phase change).
    An autopilot now has them all before its first command."""
    check = ("import numpy as np\n"
             "from vehicles import Autopilot, AutopilotConfig, load_airframe\n"
             "from vehicles import _transitions as t\n"
             "Autopilot(load_airframe('configs/airframes/bebop2.yaml'), AutopilotConfig(), 4)\n"
             "missing = [name for name in t.__all__ if not getattr(t, name).signatures]\n"
             "print('missing', missing)\n")
    done = subprocess.run([sys.executable, "-c", check], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == "missing []", done.stdout
