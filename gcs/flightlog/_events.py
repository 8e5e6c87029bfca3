"""A flight's events as an operator reads them: one line per condition, with its count.

The GCS logs a warning once per vehicle (four vehicles going stale are four
STATUSTEXTs, repeated at every phase change), so a list of the raw texts
buries the one that matters. :func:`event_lines` folds the texts that say the
same thing into one line: the vehicles it covers, how often, when first.
Two texts say the same thing when they differ only in the vehicle they name
and in their measured numbers (``0.63 m from the centroid``); the line keeps
the wording of the first occurrence.
"""

from __future__ import annotations

import re
from collections.abc import Collection, Iterable
from dataclasses import dataclass, field

__all__ = ["LEVELS", "EventLine", "event_lines", "id_ranges"]

LEVELS = ("emergency", "alert", "critical", "error", "warning", "notice", "info", "debug")
"""MAVLink's ``MAV_SEVERITY`` names, by value."""

_VEHICLE = re.compile(r"^vehicle (\d+)\b:?\s*")
_MEASURED = re.compile(r"[-+]?\d+\.\d+")


@dataclass(frozen=True)
class EventLine:
    """One condition of a flight: how often it was logged, for which vehicles, since when."""

    first_s: float
    """Time of its first occurrence, s from the start of the log."""
    level: str
    """Severity name (:data:`LEVELS`)."""
    text: str
    """The condition in the words of its first occurrence, the vehicle's name taken out."""
    count: int
    """How many times it was logged (once per vehicle per occurrence)."""
    vehicles: tuple[int, ...]
    """The vehicles it covers, ascending; empty for a team-wide event."""

    def to_json(self) -> dict[str, object]:
        """The line as summary.json holds it."""
        return {"first_s": self.first_s, "level": self.level, "count": self.count,
                "vehicles": list(self.vehicles), "text": self.text}


@dataclass
class _Group:
    first: float
    text: str
    count: int = 0
    vehicles: set[int] = field(default_factory=set)


def event_lines(texts: Iterable[tuple[float, int, int, str]], t0: float,
                vehicles: Collection[int] = ()) -> list[EventLine]:
    """Fold ``(t, sysid, severity, text)`` records into one :class:`EventLine` per condition.

    A text naming ``vehicle N`` is about vehicle N; a text a vehicle sent itself
    (its system in ``vehicles``) is about that vehicle. Lines come in the order of
    their first occurrence; ``t0`` is the start the times count from.
    """
    groups: dict[tuple[int, str], _Group] = {}
    for t, sysid, severity, raw in texts:
        match = _VEHICLE.match(raw)
        if match is not None:
            about: int | None = int(match.group(1))
            text = raw[match.end():]
        else:
            about = sysid if sysid in vehicles else None
            text = raw
        key = (severity, _MEASURED.sub("#", text))
        group = groups.setdefault(key, _Group(t, text))
        if t < group.first:  # a log's records are in time order, but say what is meant
            group.first, group.text = t, text
        group.count += 1
        if about is not None:
            group.vehicles.add(about)
    lines = [EventLine(first_s=round(g.first - t0, 2), level=_level(severity), text=g.text,
                       count=g.count, vehicles=tuple(sorted(g.vehicles)))
             for (severity, _), g in groups.items()]
    return sorted(lines, key=lambda line: line.first_s)


def id_ranges(ids: Iterable[int]) -> str:
    """``1–4, 7`` for vehicles 1, 2, 3, 4 and 7: short for a team of dozens."""
    out: list[str] = []
    run: list[int] = []
    for i in sorted(set(ids)):
        if run and i != run[-1] + 1:
            out.append(_run(run))
            run = []
        run.append(i)
    if run:
        out.append(_run(run))
    return ", ".join(out)


def _run(run: list[int]) -> str:
    if len(run) > 2:
        return f"{run[0]}–{run[-1]}"
    return ", ".join(map(str, run))


def _level(severity: int) -> str:
    return LEVELS[severity] if 0 <= severity < len(LEVELS) else f"severity {severity}"
