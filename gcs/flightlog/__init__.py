"""Flight logs: the recorder, reading .tlog files of any length, metrics, reports.

:class:`TlogRecorder` writes every frame plus the guidance internals as plain
MAVLink; :class:`TlogIndex` indexes a log in one compiled pass and decodes
only what is asked; :class:`FlightLog` is a flight as arrays;
:class:`FlightMetrics` is shared by ``gcs fly`` and ``gcs report``;
:func:`event_lines` folds a flight's events into one line per condition.

Modules:

    ``_columns``   One message type's fields as numpy columns, decoded from many logged
                   frames at once.
    ``_events``    A flight's events as an operator reads them: one line per condition,
                   with its count.
    ``_figstyle``  How every report figure looks: a colour per vehicle, the phase key,
                   legends off the data, limits marked, SVG and 200 dpi PNG files.
    ``_flight``    A recorded flight read back as arrays: guidance ticks, vehicle tracks,
                   events.
    ``_metrics``   Flight metrics: how well a flight kept its shape, calmed its payload,
                   used its limits.
    ``_reader``    Random access to .tlog files of any length: index once, decode only what
                   is asked.
    ``_recorder``  Flight recorder: every MAVLink frame in and out, plus the GCS's own
                   internals, as a .tlog.
    ``_report``    ``gcs report``: figures and a summary of a recorded flight.
    ``_shades``    The phases' colours on a time axis (report figures, exported replay).
    ``_scan``      One compiled pass over a .tlog's bytes: where each checked MAVLink frame
                   is.
"""

from collections.abc import Callable
from pathlib import Path
from typing import Any

from gcs.flightlog._events import EventLine, event_lines
from gcs.flightlog._flight import FlightLog, Track, tilt_angle
from gcs.flightlog._metrics import FlightMetrics
from gcs.flightlog._reader import LogError, TlogIndex
from gcs.flightlog._recorder import TlogRecorder
from gcs.flightlog._shades import PHASE_SHADES

__all__ = [
    "PHASE_SHADES",
    "EventLine",
    "FlightLog",
    "FlightMetrics",
    "LogError",
    "TlogIndex",
    "TlogRecorder",
    "Track",
    "event_lines",
    "tilt_angle",
    "write_report",
]


def write_report(log: FlightLog, out: Path,
                 progress: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Write the figures and summaries of ``log`` into ``out``; returns the summary.

    ``_report`` (and matplotlib, 0.35 s) loads on the first call: the GCS and the
    simulators import this package for the recorder and never draw."""
    from gcs.flightlog._report import write_report as write

    return write(log, out, progress)
