"""A second host on this machine: a network namespace joined to this one by a veth pair.

Why: a GCS and a simulator on two machines of a lab network meet each other
through real interfaces and addresses, not loopback. ``ip netns`` gives a
process its own network stack, so a test can run the simulator "on another
host" and reach it only through the pair's addresses. Needs root (or
CAP_NET_ADMIN) and iproute2.
"""

from __future__ import annotations

import itertools
import os
import shutil
import subprocess

__all__ = ["Host", "NetnsUnavailableError"]

_count = itertools.count(1)


class NetnsUnavailableError(RuntimeError):
    """This machine cannot make network namespaces (not root, no iproute2); says why."""


def _ip(*args: str) -> None:
    out = subprocess.run(["ip", *args], capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise NetnsUnavailableError(f"ip {' '.join(args)}: {out.stderr.strip() or 'failed'}")


class Host:
    """A namespace with address ``address`` on a veth pair whose other end (``gateway``)
    stays in this namespace. ``command(...)`` prefixes a command to run on that host."""

    def __init__(self) -> None:
        if shutil.which("ip") is None:
            raise NetnsUnavailableError("iproute2's ip command is not installed")
        k = (os.getpid() % 200) * 50 + next(_count) % 50
        self.name = f"gcs-host-{os.getpid()}-{k}"
        self._veth = f"vg{k}"
        subnet = f"10.{200 + k // 250 % 50}.{k % 250}"
        self.gateway, self.address = f"{subnet}.1", f"{subnet}.2"
        _ip("netns", "add", self.name)
        try:
            _ip("link", "add", self._veth, "type", "veth", "peer", "name", "eth0", "netns",
                self.name)
            _ip("addr", "add", f"{self.gateway}/24", "dev", self._veth)
            _ip("link", "set", self._veth, "up")
            _ip("-n", self.name, "addr", "add", f"{self.address}/24", "dev", "eth0")
            _ip("-n", self.name, "link", "set", "eth0", "up")
            _ip("-n", self.name, "link", "set", "lo", "up")
        except NetnsUnavailableError:
            self.close()
            raise

    def command(self, *argv: str) -> list[str]:
        """``argv`` run inside this host's namespace."""
        return ["ip", "netns", "exec", self.name, *argv]

    def close(self) -> None:
        """Remove the namespace and the pair (idempotent)."""
        subprocess.run(["ip", "link", "del", self._veth], capture_output=True, check=False)
        subprocess.run(["ip", "netns", "del", self.name], capture_output=True, check=False)

    def __enter__(self) -> Host:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
