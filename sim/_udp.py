"""Plain MAVLink over UDP for each simulated vehicle, as an autopilot's SITL offers it.

Why: MAVProxy, QGroundControl or any pymavlink script should reach a
simulated vehicle without zenoh. The convention is PX4 SITL's:

- vehicle ``k`` (0-based, team order) owns UDP port ``base + k`` on 127.0.0.1
  (default base 18570, PX4 SITL's GCS-link ports);
- it sends everything to the ground-station port 127.0.0.1:14550, where QGC
  and ``mavproxy.py --master=udpin:0.0.0.0:14550`` listen, so they discover
  all vehicles by themselves (``--udp-gcs-port 0`` turns that off);
- it also answers whoever sends it a frame, so ``udpout:127.0.0.1:<base+k>``
  (MAVProxy ``--master``, pymavlink ``mavlink_connection``) works for one
  vehicle, starting with the client's first heartbeat.

One receiver thread serves all ports and hands each datagram to the host
(which echoes setpoints at once and queues the rest for its loop). Peers are
learned on that thread and frames sent from any thread: a vehicle's peer list
is replaced whole, never edited in place, so a send sees a consistent list.
"""

from __future__ import annotations

import contextlib
import logging
import selectors
import socket
import threading
from collections.abc import Callable

from gcs.common import join_thread

__all__ = ["DEFAULT_BASE_PORT", "DEFAULT_GCS_PORT", "MAX_PEERS", "UdpPorts"]

_log = logging.getLogger(__name__)

DEFAULT_BASE_PORT = 18570
"""Port of the first vehicle (PX4 SITL's first GCS-link port)."""

DEFAULT_GCS_PORT = 14550
"""The ground-station port QGroundControl and MAVProxy listen on."""

MAX_PEERS = 4
"""Learned peers kept per vehicle (most recent first); a restarted client replaces its old port."""

_HOST = "127.0.0.1"


class UdpPorts:
    """One bound UDP socket per vehicle on 127.0.0.1; call :meth:`close` when done.

    ``on_datagram(index, data, peer)`` runs on the receiver thread.
    Binding a port that is taken raises OSError naming it.
    """

    def __init__(self, n_vehicles: int, *, base_port: int, gcs_port: int | None,
                 on_datagram: Callable[[int, bytes, tuple[str, int]], None]) -> None:
        if not 1 <= base_port <= 65535 - (n_vehicles - 1):
            raise ValueError(f"UDP base port {base_port} leaves no room for {n_vehicles} vehicles")
        self._gcs = (_HOST, gcs_port) if gcs_port else None
        self._on_datagram = on_datagram
        self._sockets: list[socket.socket] = []
        try:
            for k in range(n_vehicles):
                sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                self._sockets.append(sock)
                try:
                    sock.bind((_HOST, base_port + k))
                except OSError as exc:
                    raise OSError(exc.errno, f"cannot bind UDP {_HOST}:{base_port + k} for "
                                             f"vehicle {k}: {exc.strerror}") from None
                sock.setblocking(False)
        except BaseException:
            for sock in self._sockets:
                sock.close()
            raise
        self._peers: list[list[tuple[str, int]]] = [[] for _ in range(n_vehicles)]
        self._wake_r, self._wake_w = socket.socketpair()
        self._closed = False
        self._thread = threading.Thread(target=self._receive_loop, name="sim-udp-rx",
                                        daemon=True)
        self._thread.start()

    @property
    def ports(self) -> tuple[int, ...]:
        """Bound port of each vehicle, team order."""
        return tuple(int(s.getsockname()[1]) for s in self._sockets)

    @property
    def gcs_port(self) -> int | None:
        """The ground-station port every vehicle sends to (None: only learned peers)."""
        return None if self._gcs is None else self._gcs[1]

    def learn(self, index: int, peer: tuple[str, int]) -> None:
        """Answer ``peer`` from now on (it sent vehicle ``index`` a frame)."""
        peers = self._peers[index]
        if peers and peers[0] == peer:
            return
        self._peers[index] = [peer, *(p for p in peers if p != peer)][:MAX_PEERS]

    def send(self, index: int, frame: bytes) -> None:
        """Send one frame from vehicle ``index`` to the GCS port and every learned peer."""
        sock = self._sockets[index]
        targets = self._peers[index]
        if self._gcs is not None and self._gcs not in targets:
            targets = [self._gcs, *targets]
        for peer in targets:
            try:
                sock.sendto(frame, peer)
            except OSError:  # nobody listening, buffer full: lost, as on a radio
                _log.debug("UDP send to %s:%d failed", *peer)

    def close(self) -> None:
        """Stop the receiver and close every socket; idempotent."""
        if self._closed:
            return
        self._closed = True
        with contextlib.suppress(OSError):
            self._wake_w.send(b"x")
        join_thread(self._thread, 2.0, what="the UDP endpoints' receiver")
        for sock in (*self._sockets, self._wake_r, self._wake_w):
            sock.close()

    def _receive_loop(self) -> None:
        with selectors.DefaultSelector() as selector:
            selector.register(self._wake_r, selectors.EVENT_READ, -1)
            for k, sock in enumerate(self._sockets):
                selector.register(sock, selectors.EVENT_READ, k)
            while True:
                for key, _ in selector.select():
                    if key.data == -1:
                        return
                    self._read(key.data, self._sockets[key.data])

    def _read(self, index: int, sock: socket.socket) -> None:
        while True:
            try:
                data, peer = sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # e.g. ICMP port unreachable reported back: nothing to read
                return
            try:  # the one receiver serves every vehicle: a fault must not stop it
                self._on_datagram(index, data, (str(peer[0]), int(peer[1])))
            except Exception:
                _log.exception("UDP datagram for vehicle %d from %s:%d failed", index, *peer)
