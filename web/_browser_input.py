"""What a browser sends about its keyboard and virtual sticks, and how it is read.

viser 1.1.1 has no key-up events (its command hotkeys fire on key-down only)
and no joystick widget, so the page runs a small script (see
:mod:`web._browser_script`) that tracks held keys and the two virtual sticks
and writes its state, as one line of text, into a read-only viser text field
of the holder's panel. Every line is the *whole* state::

    #12 keys=forward,cw steps=grow:2,up:1 pad=0.40,-0.10 rot=0.00

``keys`` are the actions whose key is held, ``steps`` count every press of a
step key since the page opened (a count, not an event: viser's client keeps
only the latest of messages sent within 50 ms, so any single line may be
lost; the next one carries everything), ``pad`` is the translation stick
(forward, right) and ``rot`` the rotation stick, each in [-1, 1]. The script
repeats the line every 100 ms while anything is held; a browser that falls
silent for :data:`INPUT_TIMEOUT` is read as centred.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "HOLD_ACTIONS",
    "HOTKEYS",
    "INPUT_TIMEOUT",
    "STEP_ACTIONS",
    "BrowserInput",
    "InputTracker",
    "parse_input",
]

HOTKEYS: Mapping[str, str] = {
    "w": "forward", "s": "back", "a": "left", "d": "right", "q": "ccw", "e": "cw",
    "+": "grow", "=": "grow", "-": "shrink", "_": "shrink",
    "PageUp": "up", "PageDown": "down",
}
"""Browser key (``KeyboardEvent.key``, letters lower-case) -> action."""

HOLD_ACTIONS: Mapping[str, tuple[int, float]] = {
    "forward": (0, 1.0), "back": (0, -1.0), "right": (1, 1.0), "left": (1, -1.0),
    "cw": (2, 1.0), "ccw": (2, -1.0),
}
"""Held action -> (stick index: forward, right, rotate; direction). Positive rotation
is clockwise seen from above (about NED down)."""

STEP_ACTIONS: tuple[str, ...] = ("grow", "shrink", "up", "down")
"""Actions taken once per key press: scale and altitude steps."""

INPUT_TIMEOUT = 0.5
"""A browser silent this long (wall s) is read as centred sticks and released keys."""

_LINE = re.compile(r"#(\d+) keys=([a-z,]*) steps=([a-z:0-9,]*) "
                   r"pad=(-?[0-9.]+),(-?[0-9.]+) rot=(-?[0-9.]+)")


@dataclass(frozen=True)
class BrowserInput:
    """One line from the page's input script."""

    seq: int
    held: frozenset[str]
    steps: Mapping[str, int] = field(default_factory=dict)
    pad: tuple[float, float] = (0.0, 0.0)  # forward, right in [-1, 1]
    rotate: float = 0.0  # [-1, 1], positive clockwise from above

    def sticks(self) -> tuple[float, float, float]:
        """(forward, right, rotate) in [-1, 1]: the sticks plus the held keys."""
        s = np.array([self.pad[0], self.pad[1], self.rotate])
        for action in self.held:
            index, sign = HOLD_ACTIONS[action]
            s[index] += sign
        f, r, w = np.clip(s, -1.0, 1.0)
        return float(f), float(r), float(w)


def parse_input(text: str) -> BrowserInput | None:
    """Read one line; None if it is not one (e.g. empty, or typed by hand)."""
    m = _LINE.fullmatch(text.strip())
    if m is None:
        return None
    held = frozenset(k for k in m.group(2).split(",") if k)
    if not held <= HOLD_ACTIONS.keys():
        return None
    steps: dict[str, int] = {}
    for item in filter(None, m.group(3).split(",")):
        name, _, count = item.partition(":")
        if name not in STEP_ACTIONS or not count.isdigit():
            return None
        steps[name] = int(count)
    try:
        values = [float(m.group(k)) for k in (4, 5, 6)]
    except ValueError:
        return None
    if not all(np.isfinite(values)):
        return None
    f, r, w = (float(np.clip(v, -1.0, 1.0)) for v in values)
    return BrowserInput(seq=int(m.group(1)), held=held, steps=steps, pad=(f, r), rotate=w)


class InputTracker:
    """The latest input of one browser and the step presses not yet acted on."""

    def __init__(self) -> None:
        self._latest: BrowserInput | None = None
        self._received = -np.inf
        self._counted: dict[str, int] = {}

    def update(self, inp: BrowserInput, *, wall: float) -> dict[str, int]:
        """Take a line received at wall time ``wall``; returns new presses per step action.

        Lines older than the latest (by sequence number) are ignored.
        """
        if self._latest is not None and inp.seq <= self._latest.seq:
            return {}
        self._latest = inp
        self._received = wall
        new: dict[str, int] = {}
        for name, count in inp.steps.items():
            delta = count - self._counted.get(name, 0)
            if delta > 0:
                new[name] = delta
            self._counted[name] = count
        return new

    def sticks(self, *, wall: float) -> tuple[float, float, float]:
        """(forward, right, rotate) now; centred when the browser fell silent."""
        if self._latest is None or wall - self._received > INPUT_TIMEOUT:
            return 0.0, 0.0, 0.0
        return self._latest.sticks()

    def reset(self) -> None:
        """Forget the held state (control changed hands); counts are kept."""
        if self._latest is not None:
            self._latest = BrowserInput(seq=self._latest.seq, held=frozenset(),
                                        steps=self._latest.steps)
