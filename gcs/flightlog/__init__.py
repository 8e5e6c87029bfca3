"""Flight logs: the recorder, reading .tlog files of any length, metrics, reports.

:class:`TlogRecorder` writes every frame plus the guidance internals as plain
MAVLink; :class:`TlogIndex` indexes a log in one compiled pass and decodes
only what is asked; :class:`FlightLog` is a flight as arrays;
:class:`FlightMetrics` is shared by ``gcs fly`` and ``gcs report``.

Modules:

    ``_columns``   One message type's fields as numpy columns, decoded from many logged
                   frames at once.
    ``_flight``    A recorded flight read back as arrays: guidance ticks, vehicle tracks,
                   events.
    ``_metrics``   Flight metrics: how well a flight kept its shape, calmed its payload,
                   used its limits.
    ``_reader``    Random access to .tlog files of any length: index once, decode only what
                   is asked.
    ``_recorder``  Flight recorder: every MAVLink frame in and out, plus the GCS's own
                   internals, as a .tlog.
    ``_report``    ``gcs report``: figures and a summary of a recorded flight.
    ``_scan``      One compiled pass over a .tlog's bytes: where each checked MAVLink frame
                   is.
"""

from gcs.flightlog._columns import CHUNK, decode_columns, wire_dtype
from gcs.flightlog._flight import EARTH_RADIUS_M, ORIGIN_TOLERANCE_M, FlightLog, Track, tilt_angle
from gcs.flightlog._metrics import FlightMetrics, swing_angle
from gcs.flightlog._reader import LogError, TlogIndex, msg_id
from gcs.flightlog._recorder import (
    ARRAY_SPAN,
    ARRAYS,
    TeamHeader,
    TlogRecorder,
    chunked,
    parse_team_header,
    team_header,
)
from gcs.flightlog._report import (
    FIGURES,
    PAIRS_DRAWN,
    PLOT_BUCKETS,
    envelope,
    vehicle_distances,
    write_report,
)
from gcs.flightlog._scan import (
    CHUNK_RECORDS,
    CRC_EXTRA,
    SCAN_FIELDS,
    T_MAX_US,
    T_MIN_US,
    Scan,
    map_file,
    release_pages,
    scan_buffer,
    scan_records,
)

__all__ = [
    "ARRAYS",
    "ARRAY_SPAN",
    "CHUNK",
    "CHUNK_RECORDS",
    "CRC_EXTRA",
    "EARTH_RADIUS_M",
    "FIGURES",
    "ORIGIN_TOLERANCE_M",
    "PAIRS_DRAWN",
    "PLOT_BUCKETS",
    "SCAN_FIELDS",
    "T_MAX_US",
    "T_MIN_US",
    "FlightLog",
    "FlightMetrics",
    "LogError",
    "Scan",
    "TeamHeader",
    "TlogIndex",
    "TlogRecorder",
    "Track",
    "chunked",
    "decode_columns",
    "envelope",
    "map_file",
    "msg_id",
    "parse_team_header",
    "release_pages",
    "scan_buffer",
    "scan_records",
    "swing_angle",
    "team_header",
    "tilt_angle",
    "vehicle_distances",
    "wire_dtype",
    "write_report",
]
