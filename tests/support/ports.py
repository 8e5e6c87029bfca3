"""Free ports on loopback for the processes a test starts."""

from __future__ import annotations

import contextlib
import random
import socket


def free_udp_ports(count: int) -> int:
    """The first of ``count`` consecutive UDP ports on 127.0.0.1 that were free a moment
    ago (a simulator's vehicles listen on consecutive ports)."""
    for _ in range(50):
        base = random.randrange(20000, 60000)
        with contextlib.ExitStack() as stack:
            try:
                for port in range(base, base + count):
                    sock = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
                    sock.bind(("127.0.0.1", port))
            except OSError:
                continue
            return base
    raise RuntimeError(f"no {count} consecutive free UDP ports on 127.0.0.1")
