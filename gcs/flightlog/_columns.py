"""One message type's fields as numpy columns, decoded from many logged frames at once.

Why: a flight log of hours holds millions of telemetry frames, and pymavlink
builds one Python object per frame (most of a kilobyte each), so reading a
long log that way needs gigabytes and minutes. Every MAVLink message type has
a fixed little-endian wire layout (MAVLink 2 only trims the payload's trailing
zero bytes, MAVLink 1 frames lack the extension fields), so the payloads of
one type are copied, zero-padded, into one byte matrix that numpy views as a
structured array: the memory of the payloads themselves and no Python work
per frame. Frames are taken in chunks so the temporary index arrays stay
small whatever the log's length.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from gcs.flightlog._scan import map_file, release_pages
from gcs.wire import MavMessage, mavlink

__all__ = ["CHUNK", "decode_columns", "wire_dtype"]

CHUNK = 16384
"""Frames per copy step: bounds the temporary (chunk, payload) index arrays."""

_V2 = 0xFD
_HEADER_V2, _HEADER_V1 = 10, 6
_STRUCT_TO_NUMPY = {"B": "u1", "b": "i1", "H": "<u2", "h": "<i2", "I": "<u4", "i": "<i4",
                    "Q": "<u8", "q": "<i8", "f": "<f4", "d": "<f8", "c": "S1"}
_TOKEN = re.compile(r"(\d*)([a-zA-Z])")


def wire_dtype(cls: type[MavMessage]) -> np.dtype:
    """The numpy dtype of ``cls``'s payload, fields in wire order under their names."""
    fmt = cls.unpacker.format.lstrip("<")
    fields: list[tuple] = []
    for name, (count, code) in zip(cls.ordered_fieldnames, _TOKEN.findall(fmt), strict=True):
        n = int(count) if count else 1
        if code == "s":
            fields.append((name, f"S{n}"))
        elif n > 1:
            fields.append((name, _STRUCT_TO_NUMPY[code], (n,)))
        else:
            fields.append((name, _STRUCT_TO_NUMPY[code]))
    dtype = np.dtype(fields)
    if dtype.itemsize != cls.unpacker.size:
        raise ValueError(f"{cls.msgname}: wire layout of {dtype.itemsize} bytes, "
                         f"pymavlink says {cls.unpacker.size}")
    return dtype


def decode_columns(path: str | Path, offset: np.ndarray, records: np.ndarray,
                   name: str) -> np.ndarray:
    """Fields of the ``name`` messages at frame ``offset[records]`` of ``path``, as one array.

    ``offset`` is where each frame starts (its magic byte, after the log's
    timestamp); the frames must be of type ``name`` and checked (the index
    does that). Returns a structured array with one row per record.
    """
    cls = _message_class(name)
    dtype = wire_dtype(cls)
    out = np.zeros(len(records), dtype=dtype)
    if not len(records):
        return out
    raw = out.view(np.uint8).reshape(len(records), dtype.itemsize)
    columns = np.arange(dtype.itemsize)
    buf = map_file(Path(path))
    for lo in range(0, len(records), CHUNK):
        starts = offset[records[lo : lo + CHUNK]].astype(np.int64)
        header = np.where(buf[starts] == _V2, _HEADER_V2, _HEADER_V1)
        length = np.minimum(buf[starts + 1].astype(np.int64), dtype.itemsize)
        at = starts[:, None] + header[:, None] + columns[None, :]
        inside = columns[None, :] < length[:, None]
        raw[lo : lo + len(starts)] = np.where(inside, buf[np.where(inside, at, 0)], 0)
        release_pages(buf)
    return out


def _message_class(name: str) -> type[MavMessage]:
    msgid = getattr(mavlink, f"MAVLINK_MSG_ID_{name.upper()}", None)
    cls = mavlink.mavlink_map.get(msgid) if isinstance(msgid, int) else None
    if cls is None:
        raise ValueError(f"unknown MAVLink message {name!r}")
    return cls
