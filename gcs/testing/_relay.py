"""A TCP relay that delays and stalls a stream as a lossy radio link would.

Why: the link between a GCS and its vehicles is often a telemetry radio (100 ms
each way, a few per cent of packets lost), and the kernel of a test machine
may lack netem. Zenoh runs over TCP, where a lost segment is not a missing
message but a stall: everything behind it waits for the retransmission. So
each direction delays every chunk by ``delay``; with probability ``loss`` a
chunk is lost and arrives a retransmission timeout (Linux's minimum, 200 ms)
later than it would have, and, as TCP delivers in order, what follows it
waits for it. Losses close together overlap, as TCP recovers them together.
"""

from __future__ import annotations

import contextlib
import random
import selectors
import socket
import threading
import time
from collections import deque

__all__ = ["RTO_S", "LossyRelay"]

RTO_S = 0.2
"""What one lost segment costs a TCP stream: Linux's minimum retransmission timeout, s."""


class LossyRelay:
    """Listens on 127.0.0.1 (or ``host``) and relays each connection to ``target``.

    Args:
        target: (host, port) to connect each accepted connection to.
        delay: one-way delay, s.
        loss: probability that a chunk is lost (and retransmitted after :data:`RTO_S`).
        seed: seed of the losses, so a run can be repeated.
        host: address to listen on.
    """

    def __init__(self, target: tuple[str, int], *, delay: float, loss: float, seed: int = 0,
                 host: str = "127.0.0.1") -> None:
        if not 0.0 <= loss < 1.0 or not delay >= 0.0:
            raise ValueError(f"relay: need 0 <= loss < 1 and delay >= 0, got {loss}, {delay}")
        self.target, self.delay, self.loss = target, delay, loss
        self._rng = random.Random(seed)
        self._server = socket.create_server((host, 0))
        self._server.settimeout(0.2)
        self.port: int = self._server.getsockname()[1]
        self._stop = threading.Event()
        self._sockets: list[socket.socket] = []
        self.losses = 0
        """Chunks 'lost' (held for a retransmission) so far."""
        self._thread = threading.Thread(target=self._accept, daemon=True, name="relay-accept")
        self._thread.start()

    def _accept(self) -> None:
        while not self._stop.is_set():
            try:
                client, _ = self._server.accept()
            except (TimeoutError, OSError):
                continue
            try:
                upstream = socket.create_connection(self.target, timeout=5.0)
            except OSError:
                client.close()
                continue
            upstream.settimeout(None)
            self._sockets += [client, upstream]
            for a, b in ((client, upstream), (upstream, client)):
                threading.Thread(target=self._pipe, args=(a, b), daemon=True,
                                 name="relay-pipe").start()

    def _pipe(self, src: socket.socket, dst: socket.socket) -> None:
        """Bytes from ``src`` reach ``dst`` ``delay`` later, in order; a loss holds the rest."""
        queue: deque[tuple[float, bytes]] = deque()
        ready = threading.Condition()
        closed = threading.Event()

        def deliver() -> None:
            while True:
                with ready:
                    while not queue and not closed.is_set():
                        ready.wait(0.05)
                    if not queue:
                        dst.close()
                        return
                    due, data = queue[0]
                wait = due - time.monotonic()
                if wait > 0:  # the head holds back everything behind it: in-order delivery
                    time.sleep(min(wait, 0.005))
                    continue
                with ready:
                    queue.popleft()
                try:
                    dst.sendall(data)
                except OSError:
                    return

        threading.Thread(target=deliver, daemon=True, name="relay-deliver").start()
        sel = selectors.DefaultSelector()
        sel.register(src, selectors.EVENT_READ)
        try:
            while not self._stop.is_set():
                if not sel.select(0.2):
                    continue
                try:
                    data = src.recv(65536)
                except OSError:
                    data = b""
                if not data:
                    break
                due = time.monotonic() + self.delay
                if self._rng.random() < self.loss:  # lost: retransmitted after the timeout
                    self.losses += 1
                    due += RTO_S
                with ready:
                    queue.append((due, data))
                    ready.notify()
        finally:
            sel.close()
            closed.set()

    def close(self) -> None:
        """Stop accepting and close every relayed connection."""
        self._stop.set()
        self._server.close()
        for s in self._sockets:
            with contextlib.suppress(OSError):
                s.close()
        self._thread.join(timeout=1.0)

    def __enter__(self) -> LossyRelay:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
