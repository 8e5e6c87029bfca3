"""What the page's script sends, how the server reads it, and who may steer."""

from __future__ import annotations

import json
import re

import pytest

from web._browser_input import (
    HOLD_ACTIONS,
    HOTKEYS,
    INPUT_TIMEOUT,
    STEP_ACTIONS,
    InputTracker,
    parse_input,
)
from web._browser_script import (
    ABORT_ANSWERS,
    ABORT_HOTKEY,
    ABORT_MODIFIER,
    BEAT_PERIOD_S,
    CHANNEL_LABEL,
    RECONNECT_AFTER_S,
    RECONNECT_MAX_S,
    SEND_PERIOD_MS,
    STALE_AFTER_S,
    abort_keys,
    pads_html,
    script_source,
)
from web._control_lock import ControlLock


def line(seq: int, keys: str = "", steps: str = "", pad: str = "0.00,0.00",
         rot: str = "0.00") -> str:
    return f"#{seq} keys={keys} steps={steps} pad={pad} rot={rot}"


def test_a_line_is_read_whole() -> None:
    inp = parse_input(line(7, "forward,cw", "grow:2,up:1", "0.40,-0.25", "0.10"))
    assert inp is not None
    assert inp.seq == 7 and inp.held == {"forward", "cw"}
    assert dict(inp.steps) == {"grow": 2, "up": 1}
    assert inp.pad == (0.4, -0.25) and inp.rotate == 0.1


@pytest.mark.parametrize("text", [
    "", "w", "#1 keys=jump steps= pad=0.00,0.00 rot=0.00",
    "#1 keys= steps=explode:1 pad=0.00,0.00 rot=0.00",
    "#1 keys= steps= pad=nan,0.00 rot=0.00", "#x keys= steps= pad=0,0 rot=0",
    "#1 keys= steps=grow:two pad=0.00,0.00 rot=0.00",
])
def test_anything_else_is_ignored(text: str) -> None:
    assert parse_input(text) is None


def test_sticks_add_keys_to_the_pads_and_stay_in_range() -> None:
    inp = parse_input(line(1, "forward,left,cw", pad="0.50,0.20", rot="-0.30"))
    assert inp is not None
    assert inp.sticks() == (1.0, pytest.approx(-0.8), pytest.approx(0.7))
    both = parse_input(line(2, "forward,back"))
    assert both is not None and both.sticks() == (0.0, 0.0, 0.0)
    clipped = parse_input(line(3, pad="3.00,-9.00", rot="2.00"))
    assert clipped is not None and clipped.sticks() == (1.0, -1.0, 1.0)


def test_every_hotkey_is_an_action_the_server_knows() -> None:
    assert set(HOTKEYS.values()) == set(HOLD_ACTIONS) | set(STEP_ACTIONS)
    for key, action in {"w": "forward", "s": "back", "a": "left", "d": "right", "q": "ccw",
                        "e": "cw", "+": "grow", "-": "shrink", "PageUp": "up",
                        "PageDown": "down"}.items():
        assert HOTKEYS[key] == action


def test_step_presses_count_once_even_when_lines_repeat_or_are_lost() -> None:
    tracker = InputTracker()
    assert tracker.update(parse_input(line(1, steps="grow:1")), wall=0.0) == {"grow": 1}
    assert tracker.update(parse_input(line(2, steps="grow:1")), wall=0.1) == {}
    # lines 3 and 4 were lost: line 5 still carries both presses
    assert tracker.update(parse_input(line(5, steps="grow:3,down:1")), wall=0.2) == \
        {"grow": 2, "down": 1}
    assert tracker.update(parse_input(line(4, steps="grow:9")), wall=0.3) == {}  # stale


def test_a_silent_browser_reads_as_centred() -> None:
    tracker = InputTracker()
    assert tracker.sticks(wall=0.0) == (0.0, 0.0, 0.0)
    tracker.update(parse_input(line(1, "forward")), wall=10.0)
    assert tracker.sticks(wall=10.0 + 0.9 * INPUT_TIMEOUT) == (1.0, 0.0, 0.0)
    assert tracker.sticks(wall=10.0 + 1.1 * INPUT_TIMEOUT) == (0.0, 0.0, 0.0)


def test_reset_lets_go_but_keeps_the_counts() -> None:
    tracker = InputTracker()
    tracker.update(parse_input(line(1, "cw", "up:2", rot="0.50")), wall=0.0)
    tracker.reset()
    assert tracker.sticks(wall=0.0) == (0.0, 0.0, 0.0)
    assert tracker.update(parse_input(line(2, "cw", "up:2")), wall=0.1) == {}


def test_the_script_is_configured_from_the_python_tables() -> None:
    source = script_source()
    config = json.loads(re.search(r"const CFG = (\{.*?\});", source).group(1))  # type: ignore[union-attr]
    abort = config.pop("abort")
    fresh = config.pop("fresh")
    assert config == {"channel": CHANNEL_LABEL, "keys": dict(HOTKEYS),
                      "steps": list(STEP_ACTIONS), "period": SEND_PERIOD_MS,
                      "linger": int(INPUT_TIMEOUT * 1000)}
    # the freshness badge: stale, then reconnecting, after the server's own figures
    assert (fresh["stale"], fresh["reconnect"], fresh["reconnectMax"]) == (
        STALE_AFTER_S, RECONNECT_AFTER_S, RECONNECT_MAX_S)
    assert BEAT_PERIOD_S < STALE_AFTER_S / 3 < RECONNECT_AFTER_S  # beats to spare
    assert "st.beat = (t, age) =>" in source  # what beat() calls
    # the overlay presses the abort command's own hotkey: Ctrl+Shift+X, as registered
    assert (abort["key"], abort["ctrl"], abort["shift"], abort["alt"]) == (
        ABORT_HOTKEY, True, True, False)
    assert ABORT_MODIFIER == "cmd/ctrl+shift" and abort_keys() == "Ctrl+Shift+X"
    # the keyboard's own presses are read by the physical key (any layout); the answers
    # the button shows are the ones the server sends (answer_abort) or its silence
    assert abort["code"] == "KeyX" and abort["answers"] == ABORT_ANSWERS
    assert abort_keys() in abort["title"]
    # the line the script writes is the one the server reads
    assert '"#" + st.seq + " keys=" +' in source and '" pad=" +' in source


def test_pads_are_inert_when_disabled() -> None:
    on, off = pads_html(enabled=True), pads_html(enabled=False)
    for html in (on, off):
        assert 'data-gcs-pad="move"' in html and 'data-gcs-pad="turn"' in html
    assert "data-gcs-off" not in on and "data-gcs-off" in off


def test_one_holder_at_a_time() -> None:
    lock = ControlLock()
    assert lock.holder is None and not lock.holds(None)
    assert lock.take(3) is None
    assert lock.holds(3) and not lock.holds(4)
    assert lock.take(4) == 3  # handed over
    assert not lock.release(3) and lock.holder == 4
    assert lock.release(4) and lock.holder is None
