"""Events grouped as an operator reads them: one line per condition, not per vehicle.

The loop reports per vehicle ("vehicle 3: no fresh telemetry for 0.61 s: motion
frozen"), so one cause (a stalled simulator, a radio down) raised four lines at
once, and a repeated one filled the page's list within seconds. Here a
*condition* is an event's text without its vehicle and with its numbers taken
out, at its level: every "no fresh telemetry for … s: motion frozen" warning is
one condition, whichever vehicle and however many seconds.

* :func:`conditions`: one :class:`EventLine` per condition over the whole
  flight, with its count and the vehicles it covered, latest first: what is
  going on, at a glance.
* :func:`bursts`: the log, in time order, with the events of one condition
  that come together (within ``window`` s of each other) as one line.

Plain functions over anything with ``t``, ``level`` and ``text`` (the loop's
:class:`~gcs.loop.Event`, a replayed :class:`~web._replay.ReplayEvent`).
:class:`EventLog` keeps the events of a flight beyond the loop's recent ones.
"""

from __future__ import annotations

import collections
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Protocol

__all__ = ["LEVELS", "EventLike", "EventLine", "EventLog", "bursts", "condition",
           "conditions", "split_vehicle"]

LEVELS = ("info", "warning", "error")
"""Event levels, least severe first."""

_VEHICLE = re.compile(r"^(?:vehicle )?(\d{1,3}): (.*)$", re.DOTALL)
_MENTION = re.compile(r"\bvehicle (\d{1,3})\b")
_NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


class EventLike(Protocol):
    """What an event needs for grouping."""

    @property
    def t(self) -> float: ...

    @property
    def level(self) -> str: ...

    @property
    def text(self) -> str: ...


@dataclass(frozen=True)
class EventLine:
    """The events of one condition shown as one line."""

    t: float  # the latest one's time, s
    first_t: float  # the first one's time, s
    level: str
    text: str  # the latest one's text, without its vehicle
    count: int
    vehicles: tuple[int, ...]  # the vehicles it covered, ascending (empty: none named)
    whole: str = ""  # the latest one's text as it came

    def describe(self) -> str:
        """A lone event as it came; else ``text ×count — vehicles 1,2,3`` (the count and
        vehicles only where they say something)."""
        if self.count == 1 and self.whole:
            return self.whole
        out = self.text
        if self.count > 1:
            out += f" ×{self.count}"
        if self.vehicles:
            noun = "vehicle" if len(self.vehicles) == 1 else "vehicles"
            out += f" — {noun} {','.join(map(str, self.vehicles))}"
        return out


def split_vehicle(text: str) -> tuple[int | None, str]:
    """The vehicle an event is about and its text without it: "vehicle 3: …" and a
    vehicle's own "3: …" lose the prefix, "… vehicle 3 …" its number; (None, text)."""
    m = _VEHICLE.match(text)
    if m:
        return int(m.group(1)), m.group(2)
    m = _MENTION.search(text)
    if m:
        return int(m.group(1)), f"{text[:m.start()]}vehicle{text[m.end():]}"
    return None, text


def condition(level: str, text: str) -> tuple[str, str]:
    """The condition an event belongs to: its level and its text without its vehicle and
    with each number replaced by ``#``."""
    return level, _NUMBER.sub("#", split_vehicle(text)[1])


class _Group:
    __slots__ = ("count", "first_t", "level", "t", "text", "vehicles", "whole")

    def __init__(self, t: float, level: str, text: str) -> None:
        self.t = self.first_t = t
        self.level, self.text, self.whole = level, text, text
        self.count = 0
        self.vehicles: set[int] = set()

    def add(self, t: float, vehicle: int | None, text: str, whole: str) -> None:
        self.count += 1
        self.t, self.text, self.whole = max(self.t, t), text, whole
        if vehicle is not None:
            self.vehicles.add(vehicle)

    def line(self) -> EventLine:
        return EventLine(t=self.t, first_t=self.first_t, level=self.level, text=self.text,
                         count=self.count, vehicles=tuple(sorted(self.vehicles)),
                         whole=self.whole)


def conditions(events: Iterable[EventLike], *,
               levels: Sequence[str] = ("warning", "error")) -> list[EventLine]:
    """One line per condition among the events at ``levels``, the latest first."""
    groups: dict[tuple[str, str], _Group] = {}
    for e in events:
        if e.level not in levels:
            continue
        vehicle, rest = split_vehicle(e.text)
        key = condition(e.level, e.text)
        group = groups.get(key)
        if group is None:
            group = groups[key] = _Group(e.t, e.level, rest)
        group.add(e.t, vehicle, rest, e.text)
    return sorted((g.line() for g in groups.values()), key=lambda line: -line.t)


def bursts(events: Iterable[EventLike], *, window: float = 1.0) -> list[EventLine]:
    """The events in time order (oldest first), those of one condition that follow each
    other within ``window`` s as one line (its time: the burst's first)."""
    out: list[_Group] = []
    open_: dict[tuple[str, str], _Group] = {}
    for e in events:
        vehicle, rest = split_vehicle(e.text)
        key = condition(e.level, e.text)
        group = open_.get(key)
        if group is None or e.t - group.t > window:
            group = open_[key] = _Group(e.t, e.level, rest)
            out.append(group)
        group.add(e.t, vehicle, rest, e.text)
    return [g.line() for g in out]


class EventLog:
    """The events of a flight as they come, kept beyond the loop's recent ones.

    The loop keeps its latest 200 events; :meth:`take` is handed them at each
    tick and keeps what is new (by identity: the loop's deque holds the same
    objects), up to ``keep`` events.
    """

    def __init__(self, keep: int = 2000) -> None:
        self.events: collections.deque[EventLike] = collections.deque(maxlen=keep)
        self._last: EventLike | None = None

    def take(self, recent: Sequence[EventLike]) -> bool:
        """Keep the events of ``recent`` (oldest first) after the last one taken; True if
        any was new."""
        start = 0
        if self._last is not None:
            for k in range(len(recent) - 1, -1, -1):
                if recent[k] is self._last:
                    start = k + 1
                    break
        new = recent[start:]
        if not new:
            return False
        self.events.extend(new)
        self._last = new[-1]
        return True
