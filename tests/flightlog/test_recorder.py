"""The .tlog recorder: readable by pymavlink's mavutil and mavlogdump, robust to truncation."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from pymavlink import mavutil

from gcs.flightlog import TlogRecorder
from gcs.flightlog._recorder import ARRAYS
from gcs.wire import MavlinkEncoder
from tests.support.logfiles import raw_messages

EPOCH = 1_700_000_000.0
DIALECT = "ardupilotmega"  # read as Mission Planner reads a log


def record(path: Path, ticks: int = 20) -> MavlinkEncoder:
    gcs = MavlinkEncoder(system_id=245, component_id=190)
    vehicle = MavlinkEncoder(system_id=3, component_id=1)
    rec = TlogRecorder(path, encoder=gcs, epoch=EPOCH)
    for k in range(ticks):
        t = 0.25 * k
        hb = vehicle.mav.heartbeat_encode(2, 12, 129, 4, 4, 3)
        rec.frame(t, vehicle.encode(hb))
        rec.internals(t, arrays={"dist_err": np.arange(6) * 0.01 * k,
                                 "acc_cmd": np.full((70, 2), 0.5)}, sticks=(0.1, -0.2, 0.3),
                      scale=1.05, altitude=1.5, phase=6)
        if k == 5:
            rec.text(t, "phase: formation flight")
    rec.close()
    return gcs


def test_mavutil_reads_frames_internals_and_timestamps(tmp_path: Path) -> None:
    path = tmp_path / "flight.tlog"
    record(path)
    msgs = raw_messages(path, DIALECT)
    kinds = {m.get_type() for m in msgs}
    assert {"HEARTBEAT", "DEBUG_FLOAT_ARRAY", "NAMED_VALUE_FLOAT", "NAMED_VALUE_INT",
            "STATUSTEXT"} <= kinds
    hb = [m for m in msgs if m.get_type() == "HEARTBEAT"]
    assert len(hb) == 20 and hb[0].get_srcSystem() == 3
    assert hb[4]._timestamp == pytest.approx(EPOCH + 1.0)
    arrays = [m for m in msgs if m.get_type() == "DEBUG_FLOAT_ARRAY"]
    ids = sorted({m.array_id for m in arrays})
    acc = ARRAYS["acc_cmd"]
    assert ids == [ARRAYS["dist_err"], acc, acc + 1, acc + 2]
    last = [m for m in arrays if m.array_id == ARRAYS["dist_err"]][-1]
    assert last.data[:6] == pytest.approx(np.arange(6) * 0.19, abs=1e-6)
    assert arrays[0].get_srcSystem() == 245
    text = next(m for m in msgs if m.get_type() == "STATUSTEXT")
    assert text.text == "phase: formation flight"


def test_truncated_log_reads_up_to_the_cut(tmp_path: Path) -> None:
    path = tmp_path / "cut.tlog"
    record(path)
    whole = len(raw_messages(path, DIALECT))
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * 0.6) + 7])  # cut inside a record
    part = raw_messages(path, DIALECT)
    assert 0.5 * whole < len(part) < whole


def test_mavlogdump_reads_it(tmp_path: Path) -> None:
    path = tmp_path / "flight.tlog"
    record(path, ticks=3)
    dump = Path(mavutil.__file__).parent / "tools" / "mavlogdump.py"
    out = subprocess.run([sys.executable, str(dump), "--types", "NAMED_VALUE_FLOAT",
                          str(path)], capture_output=True, text=True, timeout=60, check=True)
    assert out.stdout.count("NAMED_VALUE_FLOAT") == 15
    assert "stk_fwd" in out.stdout


def test_flushed_while_open(tmp_path: Path) -> None:
    gcs = MavlinkEncoder(system_id=245, component_id=190)
    path = tmp_path / "live.tlog"
    rec = TlogRecorder(path, encoder=gcs, epoch=EPOCH, flush_interval=0.0)
    rec.text(0.0, "hello")
    assert path.stat().st_size > 8  # on disk before close: a killed GCS keeps it
    rec.close()
    rec.text(1.0, "after close is ignored")
