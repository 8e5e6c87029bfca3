"""A viewer without a browser: a websocket client of a viser page that decodes what it gets.

Why: what reaches a viewer, not what the UI thread meant to send, is the
page's real update rate (viser merges the updates of one node queued within a
send window, and a busy server sends late), and a test can check what the
scene holds (which nodes, where, visible) from the wire, whatever the
browser. ``bench/ui_update.py`` and the tests use it; from a shell it
measures what a viewer of a running page (``gcs demo``, ``gcs run``) receives::

    python -m web.wireviewer 8080 --seconds 5     # one JSON line

viser 1.1.1's wire format (``viser/infra/_infra.py``, ``_message_producer``):
each websocket message is one *window* of messages: 8 bytes decompressed
size, 8 bytes compressed size, zstd-compressed msgpack ``{"messages": [...],
"timestampSec": ..., "binaryBufferLengths": [...]}``, then the numpy arrays,
each 8-byte aligned, referenced from the messages as ``{"__binary_index": i,
"dtype": "<f4"}`` (flat: the shape is the reader's to know).
"""

from __future__ import annotations

import argparse
import json
import threading
import time
from collections.abc import Iterator
from typing import Any

import msgspec
import numpy as np
import viser
import zstandard
from viser import _messages as viser_messages
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect
from websockets.typing import Subprotocol

from gcs.common import join_thread

__all__ = ["SceneRecord", "WireViewer", "decode_window", "main", "scene_names"]

_HEADER = 16
_ALIGN = 8
CAMERA = ((-3.4, -1.0, -2.4), (0.0, 0.0, 0.0))
"""The camera :func:`main`'s viewer reports (the page's initial one, NED)."""


def _resolve(value: Any, buffers: list[np.ndarray]) -> Any:
    """``value`` with every binary placeholder replaced by its array."""
    if isinstance(value, dict):
        if "__binary_index" in value and "dtype" in value:
            return buffers[value["__binary_index"]].view(np.dtype(value["dtype"]))
        return {k: _resolve(v, buffers) for k, v in value.items()}
    if isinstance(value, list):
        return [_resolve(v, buffers) for v in value]
    return value


def decode_window(data: bytes) -> list[dict[str, Any]]:
    """The messages of one websocket message from a viser server, arrays in place."""
    size = int.from_bytes(data[:8], "little")
    compressed = int.from_bytes(data[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(data[_HEADER:_HEADER + compressed],
                                                    max_output_size=size)
    window = msgspec.msgpack.decode(inner)
    buffers: list[np.ndarray] = []
    offset = _HEADER + compressed
    raw = np.frombuffer(data, dtype=np.uint8)
    for length in window.get("binaryBufferLengths", ()):
        offset += -offset % _ALIGN
        buffers.append(raw[offset:offset + length])
        offset += length
    return [_resolve(m, buffers) for m in window["messages"]]


def scene_names(messages: list[dict[str, Any]]) -> Iterator[str]:
    """Names of the scene nodes whose state the messages change (the root is "")."""
    for m in messages:
        name = m.get("name")
        if isinstance(name, str) and m.get("type") != "GuiUpdateMessage":
            yield name


class SceneRecord:
    """What a viewer knows of the scene from the windows it received.

    Each scene node's latest properties (as created, then updated, moved,
    shown or hidden) and the arrival time of every window that changed a
    node, so a rate is what this viewer really received. Fed by
    :class:`WireViewer`, or by a browser's frames (Playwright) in the tests.
    """

    def __init__(self) -> None:
        self.received = 0
        """Bytes received so far."""
        self._nodes: dict[str, dict[str, Any]] = {}
        self._arrivals: list[tuple[float, frozenset[str]]] = []
        self._lock = threading.Lock()

    def take(self, data: bytes, at: float) -> None:
        """One websocket message from the page, received at monotonic time ``at``."""
        messages = decode_window(data)
        with self._lock:
            self.received += len(data)
            for m in messages:
                self._apply(m)
            names = frozenset(scene_names(messages))
            if names:
                self._arrivals.append((at, names))

    def _apply(self, m: dict[str, Any]) -> None:
        """Keep what one message says about a scene node (lock held)."""
        name = m.get("name")
        if not isinstance(name, str) or m.get("type") == "GuiUpdateMessage":
            return
        kind = m["type"]
        if "props" in m:  # a node (re)created
            self._nodes[name] = {"type": kind, **m["props"], "visible": True}
        node = self._nodes.setdefault(name, {"type": None})
        if kind == "SceneNodeUpdateMessage":
            node.update(m["updates"])
        elif kind == "SetPositionMessage":
            node["position"] = tuple(m["position"])
        elif kind == "SetOrientationMessage":
            node["wxyz"] = tuple(m["wxyz"])
        elif kind == "SetSceneNodeVisibilityMessage":
            node["visible"] = bool(m["visible"])
        elif kind == "RemoveSceneNodeMessage":
            self._nodes.pop(name, None)

    def node(self, name: str) -> dict[str, Any] | None:
        """The latest properties of scene node ``name`` (the root is ""), None if unknown."""
        with self._lock:
            node = self._nodes.get(name)
            return None if node is None else dict(node)

    def _times(self, name: str) -> list[float]:
        """Arrival times of the windows that changed node ``name`` or a node under it."""
        under = name.rstrip("/") + "/"
        with self._lock:
            return [t for t, names in self._arrivals
                    if name in names or any(n.startswith(under) for n in names)]

    def updates(self, name: str) -> int:
        """How many windows so far changed node ``name`` or a node under it."""
        return len(self._times(name))

    def rate(self, name: str, *, since: float) -> float:
        """Windows per second that changed node ``name`` (or a node under it) since
        monotonic time ``since``."""
        times = [t for t in self._times(name) if t >= since]
        if len(times) < 2:
            return 0.0
        return (len(times) - 1) / (times[-1] - times[0])

    def wait_for(self, name: str, timeout: float = 10.0) -> dict[str, Any]:
        """The node ``name`` once it arrived (AssertionError after ``timeout`` s)."""
        deadline = time.monotonic() + timeout
        while (node := self.node(name)) is None:
            assert time.monotonic() < deadline, f"the page never sent the scene node {name!r}"
            time.sleep(0.02)
        return node


class WireViewer(SceneRecord):
    """One viewer of the page served on ``port``: it reads, decodes and keeps what it gets.

    Args:
        port: the page's port.
        host: the page's host.
        decode: False to read and discard, counting only the bytes (:attr:`received`):
            for a viewer inside a process that measures the page's own cost, where
            decoding would be counted as that cost and compete for its GIL.
    """

    def __init__(self, port: int, *, host: str = "127.0.0.1", decode: bool = True) -> None:
        super().__init__()
        self._decode = decode
        self._stop = threading.Event()
        self._ws = connect(f"ws://{host}:{port}",
                           subprotocols=[Subprotocol(f"viser-v{viser.__version__}")], max_size=None)
        self._thread = threading.Thread(target=self._read, daemon=True, name="wire-viewer")
        self._thread.start()

    def _read(self) -> None:
        while not self._stop.is_set():
            try:
                data = self._ws.recv(timeout=0.1)
            except TimeoutError:
                continue
            except ConnectionClosed:
                return
            assert isinstance(data, bytes)
            if self._decode:
                self.take(data, time.monotonic())
            else:
                with self._lock:
                    self.received += len(data)

    def send(self, message: viser_messages.Message) -> None:
        """Send the page one message, as a browser does (a camera, a GUI value...)."""
        self._ws.send(msgspec.msgpack.encode(message.as_serializable_dict()))

    def report_camera(self, position: tuple[float, float, float],
                      look_at: tuple[float, float, float]) -> None:
        """Report a camera as a browser does (viser counts a viewer once it has one)."""
        self.send(viser_messages.ViewerCameraMessage(
            wxyz=(1.0, 0.0, 0.0, 0.0), position=position, fov=1.0, near=0.01, far=1000.0,
            image_height=600, image_width=800, look_at=look_at, up_direction=(0.0, 0.0, -1.0)))

    def settled(self, quiet: float = 0.4) -> int:
        """Bytes received once nothing more arrived for ``quiet`` seconds."""
        last = -1
        while last != self.received:
            last = self.received
            time.sleep(quiet)
        return last

    def close(self) -> None:
        self._stop.set()
        self._ws.close()
        join_thread(self._thread, 2.0, what="the wire viewer's reader")


def main(argv: list[str] | None = None) -> None:
    """Watch a page for a while; print what arrived, per second, as one JSON line."""
    parser = argparse.ArgumentParser(description=main.__doc__)
    parser.add_argument("port", type=int, help="the page's port")
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--node", default="/team",
                        help="scene node whose updates (its own or under it) are counted "
                             "(default /team: the team's frames)")
    parser.add_argument("--warmup", type=float, default=1.0, metavar="S",
                        help="seconds connected before counting (the page's backlog)")
    parser.add_argument("--seconds", type=float, default=5.0, metavar="S",
                        help="seconds counted")
    args = parser.parse_args(argv)
    viewer = WireViewer(args.port, host=args.host)
    try:
        viewer.report_camera(*CAMERA)
        time.sleep(args.warmup)
        since, received = time.monotonic(), viewer.received
        time.sleep(args.seconds)
        elapsed = time.monotonic() - since
        print(json.dumps({"node": args.node,
                          "received_rate_hz": round(viewer.rate(args.node, since=since), 2),
                          "received_kb_per_s": round((viewer.received - received) / 1e3
                                                     / elapsed, 1)}), flush=True)
    finally:
        viewer.close()


if __name__ == "__main__":
    main()
