"""One autopilot parameter read or set over MAVLink's parameter protocol, confirmed.

The GCS reads a handful of an autopilot's parameters before arming (its tilt
limit) and may set one: ``PARAM_REQUEST_READ`` is answered by ``PARAM_VALUE``;
``PARAM_SET`` is answered by a ``PARAM_VALUE`` with the value the autopilot
took, and the GCS then reads it back once more, so a set that returns is the
autopilot's own word. Unanswered requests are re-sent; what still has no answer
raises :class:`~gcs.link.LinkError` naming the vehicle and the parameter.

Integer parameters travel in the float field in one of two ways: ArduPilot
casts (``2000`` is sent as ``2000.0``), PX4 copies the bytes
(``MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE``); ``bytewise`` chooses.
"""

from __future__ import annotations

import struct
import threading
import time
from dataclasses import dataclass

from gcs.link._errors import LinkError
from gcs.link._link import Link
from gcs.wire import MavMessage, mavlink

__all__ = ["ParamClient", "ParamValue"]

_INT_FORMATS = {
    mavlink.MAV_PARAM_TYPE_UINT8: "<B", mavlink.MAV_PARAM_TYPE_INT8: "<b",
    mavlink.MAV_PARAM_TYPE_UINT16: "<H", mavlink.MAV_PARAM_TYPE_INT16: "<h",
    mavlink.MAV_PARAM_TYPE_UINT32: "<I", mavlink.MAV_PARAM_TYPE_INT32: "<i",
}
"""Integer parameter types and their byte layouts (bytewise encoding)."""


@dataclass(frozen=True)
class ParamValue:
    """One parameter as the autopilot reported it."""

    name: str
    value: float
    """Decoded value (an integer parameter's integer, as a float)."""
    param_type: int
    """``MAV_PARAM_TYPE``."""

    @property
    def is_integer(self) -> bool:
        """Whether the parameter is an integer type."""
        return self.param_type in _INT_FORMATS


def _name(raw: bytes | str) -> str:
    text = raw.decode("ascii", "replace") if isinstance(raw, bytes) else raw
    return text.split("\x00", 1)[0]


class ParamClient:
    """Reads and sets parameters of the vehicle behind one link; thread-safe, blocking.

    Never call from a link listener (the answers arrive on the receive thread).
    """

    def __init__(self, link: Link, *, bytewise: bool = False, timeout_s: float = 1.0,
                 retries: int = 2) -> None:
        self._link = link
        self._bytewise = bytewise
        self._timeout_s = timeout_s
        self._retries = retries
        self._cond = threading.Condition()
        self._latest: dict[str, tuple[int, ParamValue]] = {}  # name -> (arrival count, value)
        self._arrivals = 0
        self._busy = threading.Lock()  # one exchange at a time: answers carry no request id
        link.add_message_listener(self._on_message)

    def _on_message(self, msg: MavMessage) -> None:
        if msg.get_type() != "PARAM_VALUE" or msg.get_srcComponent() != \
                self._link.target_component:
            return
        value = ParamValue(_name(msg.param_id), self._decode(msg.param_value, msg.param_type),
                           int(msg.param_type))
        with self._cond:
            self._arrivals += 1
            self._latest[value.name] = (self._arrivals, value)
            self._cond.notify_all()

    def _decode(self, raw: float, param_type: int) -> float:
        fmt = _INT_FORMATS.get(param_type)
        if not self._bytewise or fmt is None:
            return float(raw)
        data = struct.pack("<f", raw)[:struct.calcsize(fmt)]
        return float(struct.unpack(fmt, data)[0])

    def _encode(self, value: float, param_type: int) -> float:
        fmt = _INT_FORMATS.get(param_type)
        if fmt is None:
            return float(value)
        if not self._bytewise:
            return float(round(value))
        data = struct.pack(fmt, round(value)).ljust(4, b"\x00")
        return float(struct.unpack("<f", data)[0])

    def latest(self, name: str) -> ParamValue | None:
        """The parameter as last heard (read, set, or sent unasked: an autopilot announces a
        change another ground station made), without asking; None if never heard."""
        with self._cond:
            entry = self._latest.get(name)
        return None if entry is None else entry[1]

    def read(self, name: str) -> ParamValue:
        """The parameter's current value (PARAM_REQUEST_READ); LinkError when unanswered."""
        link = self._link
        request = link.mav.param_request_read_encode(link.sysid, link.target_component,
                                                     name.encode("ascii"), -1)
        with self._busy:
            return self._exchange(name, request, what=f"parameter {name}")

    def set(self, name: str, value: float, *, param_type: int | None = None) -> ParamValue:
        """Set the parameter (PARAM_SET), then read it back; the value read back.

        ``param_type`` defaults to the type the autopilot reported for it (read
        first if not known yet).
        """
        if param_type is None:
            param_type = self.read(name).param_type
        link = self._link
        message = link.mav.param_set_encode(link.sysid, link.target_component,
                                            name.encode("ascii"),
                                            self._encode(value, param_type), param_type)
        with self._busy:
            self._exchange(name, message, what=f"the answer to setting {name}")
        return self.read(name)

    def _exchange(self, name: str, message: MavMessage, *, what: str) -> ParamValue:
        """Send ``message`` until a PARAM_VALUE named ``name`` arrives after it."""
        for _attempt in range(1 + self._retries):
            with self._cond:
                since = self._arrivals
            self._link.send_message(message)
            deadline = time.monotonic() + self._timeout_s
            with self._cond:
                while True:
                    entry = self._latest.get(name)
                    if entry is not None and entry[0] > since:
                        return entry[1]
                    remaining = deadline - time.monotonic()
                    if remaining <= 0 or self._link.closed:
                        break
                    self._cond.wait(remaining)
        raise LinkError(self._link.sysid, f"no PARAM_VALUE for {what} after "
                                          f"{1 + self._retries} attempts of {self._timeout_s:g} s")
