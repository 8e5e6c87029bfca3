"""MAVLink frames over anything ``pymavlink.mavutil`` can open: UDP, TCP, serial.

Only mavutil's byte I/O is used (``recv``/``write``); its parser is not, so a
real autopilot's bytes go through the same decoder, signing and counters as
the simulated vehicles'. A background thread waits on the port (``select``)
and hands whole reads to the link, so the GCS loop never blocks on I/O.

Connection strings: ``udpin:<ip>:<port>`` (listen; replies go to whoever
spoke last), ``udpout:<ip>:<port>``, ``tcp:<host>:<port>``,
``tcpin:<ip>:<port>``, or a serial device (``/dev/ttyACM0``; needs pyserial).
"""

from __future__ import annotations

import contextlib
import logging
import select
import threading
from collections.abc import Callable

from pymavlink import mavutil

from gcs.common import join_thread

__all__ = ["DATAGRAM_PREFIXES", "STREAM_PREFIXES", "MavutilTransport", "is_connection_string"]

_log = logging.getLogger(__name__)

DATAGRAM_PREFIXES = ("udpin:", "udpout:", "udp:", "udpbcast:")
"""Connection strings whose reads are whole datagrams."""

STREAM_PREFIXES = ("tcp:", "tcpin:")
"""Connection strings that are byte streams (serial devices are streams too)."""

_READS_PER_WAKEUP = 64


def is_connection_string(text: str) -> bool:
    """True if ``text`` looks like a mavutil connection string this transport accepts."""
    if text.startswith(DATAGRAM_PREFIXES + STREAM_PREFIXES):
        host_port = text.split(":", 1)[1]
        host, _, port = host_port.rpartition(":")
        return bool(host) and port.isdigit() and int(port) <= 65535
    return text.startswith("/dev/") or text.upper().startswith("COM")


class MavutilTransport:
    """A :class:`~gcs.transport.Transport` on a pymavlink connection it owns."""

    def __init__(self, connection: str, *, baud: int = 57600, poll_s: float = 0.05) -> None:
        if not is_connection_string(connection):
            raise ValueError(f"not a pymavlink connection string: {connection!r} (use udpin:, "
                             "udpout:, tcp:, tcpin: or a serial device path)")
        self._connection = connection
        self._datagram = connection.startswith(DATAGRAM_PREFIXES)
        try:
            self._conn = mavutil.mavlink_connection(connection, baud=baud, autoreconnect=False)
        except ImportError as exc:
            raise RuntimeError(f"{connection}: serial ports need the pyserial package "
                               f"({exc})") from None
        except OSError as exc:
            raise RuntimeError(f"cannot open {connection}: {exc.strerror or exc}") from None
        self._poll_s = poll_s
        self._write_lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.read_errors = 0
        """Exceptions while reading or delivering (logged, then counted)."""

    @property
    def datagram(self) -> bool:
        """True for UDP."""
        return self._datagram

    @property
    def description(self) -> str:
        """The connection string."""
        return self._connection

    @property
    def local_address(self) -> tuple[str, int] | None:
        """Bound (host, port) of a socket connection, None otherwise (lets tests bind port 0)."""
        port = getattr(self._conn, "port", None)
        getsockname = getattr(port, "getsockname", None)
        if getsockname is None:
            return None
        host, number = getsockname()[:2]
        return str(host), int(number)

    def start(self, on_bytes: Callable[[bytes], None]) -> None:
        """Start the reader thread."""
        if self._thread is not None:
            raise RuntimeError(f"{self._connection}: already started")
        self._thread = threading.Thread(target=self._read_loop, args=(on_bytes,),
                                        name=f"mavutil-rx {self._connection}", daemon=True)
        self._thread.start()

    def send(self, frame: bytes) -> None:
        """Write bytes to the port (UDP in: to the peers heard from; none heard yet: dropped)."""
        if self._stop.is_set():
            return
        with self._write_lock:
            try:
                self._conn.write(frame)
            except OSError:
                _log.debug("write failed on %s", self._connection)

    def close(self) -> None:
        """Stop the reader and close the port; idempotent."""
        if self._stop.is_set():
            return
        self._stop.set()
        join_thread(self._thread, 2.0, what=f"the receiver of {self._connection}")
        with self._write_lock, contextlib.suppress(OSError):
            self._conn.close()

    def _read_loop(self, on_bytes: Callable[[bytes], None]) -> None:
        conn = self._conn
        while not self._stop.is_set():
            try:
                fd = getattr(conn, "fd", None)
                if fd is not None:
                    ready, _, _ = select.select([fd], [], [], self._poll_s)
                    if not ready:
                        continue
                got_any = False
                for _ in range(_READS_PER_WAKEUP):
                    data = conn.recv(4096)
                    if not data:
                        break
                    got_any = True
                    on_bytes(bytes(data))
                if not got_any and fd is None:
                    self._stop.wait(self._poll_s / 5)
            except Exception:
                if self._stop.is_set():
                    break
                self.read_errors += 1
                _log.exception("read failed on %s", self._connection)
                self._stop.wait(self._poll_s)
