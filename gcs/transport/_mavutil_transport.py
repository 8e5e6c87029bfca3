"""MAVLink frames over anything ``pymavlink.mavutil`` can open: UDP, TCP, serial.

Only mavutil's byte I/O is used (``recv``/``write``); its parser is not, so a
real autopilot's bytes go through the same decoder, signing and counters as
the simulated vehicles'. A background thread waits on the port (``select``)
and hands whole reads to the link, so the GCS loop never blocks on I/O.

TCP is read and written here on mavutil's socket, not through mavutil: for a
peer that is gone (end of stream, reset, an autopilot that died at boot)
mavutil prints "EOF on TCP socket" at every wake-up of the reader, a tight loop
that floods the log. Here a lost peer is said once (a log warning); a
``tcp:`` link then reconnects with exponential back-off (``BACKOFF_FIRST_S``
doubling up to ``BACKOFF_CAP_S``), a ``tcpin:`` link waits for the peer to
connect again, and the first bytes after that are said once too.

Connection strings: ``udpin:<ip>:<port>`` (listen; replies go to whoever
spoke last), ``udpout:<ip>:<port>``, ``tcp:<host>:<port>``,
``tcpin:<ip>:<port>``, or a serial device (``/dev/ttyACM0``; needs pyserial).
"""

from __future__ import annotations

import contextlib
import logging
import select
import socket
import threading
import time
from collections.abc import Callable

from pymavlink import mavutil

from gcs.common import join_thread

__all__ = ["BACKOFF_CAP_S", "BACKOFF_FIRST_S", "DATAGRAM_PREFIXES", "STREAM_PREFIXES",
           "MavutilTransport", "is_connection_string"]

_log = logging.getLogger(__name__)

DATAGRAM_PREFIXES = ("udpin:", "udpout:", "udp:", "udpbcast:")
"""Connection strings whose reads are whole datagrams."""

STREAM_PREFIXES = ("tcp:", "tcpin:")
"""Connection strings that are byte streams (serial devices are streams too)."""

_READS_PER_WAKEUP = 64

BACKOFF_FIRST_S = 0.5
"""Wait before the first reconnection of a ``tcp:`` link whose peer is gone, s."""

BACKOFF_CAP_S = 8.0
"""Longest wait between reconnection attempts, s (the wait doubles up to it)."""

_CONNECT_TIMEOUT_S = 1.0
"""Longest one reconnection attempt blocks the reader, s (below close()'s join)."""


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
        self._write_lock = threading.Lock()  # also guards swapping a TCP link's socket
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._tcp = connection.startswith(STREAM_PREFIXES)
        self._lost_at: float | None = None  # monotonic time the peer went (None: connected)
        self._backoff_s = BACKOFF_FIRST_S
        self._retry_at = 0.0
        self.read_errors = 0
        """Exceptions while reading or delivering (logged, then counted)."""
        self.disconnects = 0
        """Times a TCP peer went away (end of stream or reset)."""
        self.reconnect_attempts = 0
        """Reconnection attempts of a ``tcp:`` link, failed or not."""

    @property
    def connected(self) -> bool:
        """False while a TCP link's peer is gone (UDP and serial: always True)."""
        return self._lost_at is None

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
        """Bound (host, port) of a socket connection (``tcpin:``: its listener), None
        otherwise (lets tests bind port 0)."""
        port = getattr(self._conn, "listen", None) or getattr(self._conn, "port", None)
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
        """Write bytes to the port (UDP in: to the peers heard from; none heard yet, or a
        TCP peer gone: dropped)."""
        if self._stop.is_set():
            return
        with self._write_lock:
            try:
                if self._tcp:  # not mavutil's write: it prints on every failed one
                    sock = self._conn.port
                    if sock is not None:
                        sock.send(frame)
                else:
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
            if self._conn.port is not None or not self._tcp or hasattr(self._conn, "listen"):
                self._conn.close()  # (mavutil's tcp: close fails on a socket already closed)

    def _read_loop(self, on_bytes: Callable[[bytes], None]) -> None:
        conn = self._conn
        while not self._stop.is_set():
            try:
                if self._tcp:
                    self._read_tcp(on_bytes)
                    continue
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

    # -- TCP --------------------------------------------------------------------------------

    def _read_tcp(self, on_bytes: Callable[[bytes], None]) -> None:
        """One wake-up of a TCP link's reader: read, or (re)connect when due."""
        conn = self._conn
        sock: socket.socket | None = conn.port
        if sock is None:
            listen: socket.socket | None = getattr(conn, "listen", None)
            if listen is not None:
                self._accept(listen)
            else:
                self._reconnect()
            return
        ready, _, _ = select.select([sock], [], [], self._poll_s)
        if not ready:
            return
        for _ in range(_READS_PER_WAKEUP):
            try:
                data = sock.recv(4096)
            except BlockingIOError:
                return
            except OSError as exc:
                self._lose(sock, f"connection lost ({exc.strerror or exc})")
                return
            if not data:
                self._lose(sock, "the peer closed the connection")
                return
            if self._lost_at is not None:
                _log.warning("%s: connected again after %.1f s", self._connection,
                             time.monotonic() - self._lost_at)
                self._lost_at, self._backoff_s = None, BACKOFF_FIRST_S
            on_bytes(data)

    def _lose(self, sock: socket.socket, why: str) -> None:
        """The peer is gone: close its socket, say so once, and schedule the next attempt."""
        conn = self._conn
        with self._write_lock:
            with contextlib.suppress(OSError):
                sock.close()
            conn.port = None
            listen = getattr(conn, "listen", None)
            if listen is not None:
                conn.fd = listen.fileno()
        self.disconnects += 1
        now = time.monotonic()
        first = self._lost_at is None
        if first:
            self._lost_at = now
            self._backoff_s = BACKOFF_FIRST_S
            then = ("waiting for it to connect again" if listen is not None else
                    f"reconnecting, every {BACKOFF_FIRST_S:g} s at first and at most every "
                    f"{BACKOFF_CAP_S:g} s")
            _log.warning("%s: %s; %s", self._connection, why, then)
        else:  # it came back and went again before sending anything: still backing off
            _log.debug("%s: %s again", self._connection, why)
        self._retry_at = now + self._backoff_s

    def _reconnect(self) -> None:
        """A ``tcp:`` link whose peer is gone: one connection attempt when due."""
        wait = self._retry_at - time.monotonic()
        if wait > 0:
            self._stop.wait(min(wait, self._poll_s * 4))
            return
        self.reconnect_attempts += 1
        host, port = self._conn.destination_addr
        try:
            sock = socket.create_connection((host, port), timeout=_CONNECT_TIMEOUT_S)
        except OSError as exc:
            self._backoff_s = min(2.0 * self._backoff_s, BACKOFF_CAP_S)
            self._retry_at = time.monotonic() + self._backoff_s
            _log.debug("%s: reconnection failed (%s); next in %g s", self._connection,
                       exc.strerror or exc, self._backoff_s)
            return
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        with self._write_lock:
            if self._stop.is_set():
                sock.close()
                return
            self._conn.port = sock
            self._conn.fd = sock.fileno()
        # the back-off doubles until bytes arrive: a peer that accepts and hangs up at once
        # is not reconnected to in a tight loop either
        self._backoff_s = min(2.0 * self._backoff_s, BACKOFF_CAP_S)

    def _accept(self, listen: socket.socket) -> None:
        """A ``tcpin:`` link without a peer: take the next one that connects."""
        ready, _, _ = select.select([listen], [], [], self._poll_s)
        if not ready:
            return
        try:
            sock, _address = listen.accept()
        except (BlockingIOError, InterruptedError):
            return
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        with self._write_lock:
            self._conn.port = sock
            self._conn.fd = sock.fileno()
