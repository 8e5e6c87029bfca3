"""Feeding viser from our own threads: its senders are woken on its event loop only.

The page writes to viser from threads that are not viser's event loop: the UI
thread draws, viser's thread pool runs the panels' callbacks, and both write
GUI and scene properties. Each write ends in viser 1.1.1's
``AsyncMessageBuffer.push``, which wakes the buffer's sender (one coroutine
per viewer, on the loop, parked in ``await message_event.wait()``) twice: with
``message_event.set()`` called from the writing thread, and again through
``call_soon_threadsafe``. The first is not thread-safe: ``asyncio.Event.set``
walks the event's waiters while the loop thread may be adding or removing one,
which either raises ``RuntimeError: deque mutated during iteration`` in the
writing thread (the write's caller fails: a frame half drawn, a callback cut
short), or sets the flag just before the loop registers its waiter, so the
waiter is never woken and the thread-safe second wake finds the flag already
set and does nothing. That sender then sleeps until the flag is cleared again,
which only a sender that wakes can do: for a viewer's own buffer (its panel,
camera, abort answers) and for the shared buffer of a lone viewer (the scene,
the status), never, so that viewer's page stops changing until it reconnects.

:func:`wake_on_loop` replaces the event of every buffer of a server (the
shared one, and each viewer's as it connects, before its sender starts) with
a :class:`LoopEvent`, whose ``set()`` from another thread is only handed to the
loop. The loop then sets it itself, after any waiter it is registering, so
every write wakes its sender and no writing thread walks the waiters. Writes
from any thread stay as they are; ``server.atomic()`` is unaffected (its end
wakes the senders through the loop already).
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections.abc import Iterable, Iterator

import viser
from viser.infra import WebsockClientConnection
from viser.infra._async_message_buffer import AsyncMessageBuffer

__all__ = ["LoopEvent", "leaving_allowed", "wake_on_loop"]


class LoopEvent(asyncio.Event):
    """An :class:`asyncio.Event` that any thread may set: off its loop, ``set()`` is
    handed to the loop (``call_soon_threadsafe``), which sets it."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        super().__init__()
        self._home = loop

    def set(self) -> None:
        try:
            here = asyncio.get_running_loop()
        except RuntimeError:  # a thread without a loop: the UI thread, a callback
            here = None
        if here is self._home:
            super().set()
            return
        with contextlib.suppress(RuntimeError):  # a closed loop: the server stopped
            self._home.call_soon_threadsafe(self._set_here)

    def _set_here(self) -> None:
        super().set()


def _swap(buffer: AsyncMessageBuffer) -> None:
    """Give ``buffer`` a :class:`LoopEvent` (on the loop thread only)."""
    old = buffer.message_event
    if isinstance(old, LoopEvent):
        return
    new = LoopEvent(buffer.event_loop)
    buffer.message_event = new
    if old.is_set():
        new.set()
    old.set()  # a sender parked on the old event wakes, looks for messages, waits on the new


@contextlib.contextmanager
def leaving_allowed(clients: Iterable[viser.ClientHandle]) -> Iterator[None]:
    """Write to ``clients`` without viser's warning if one of them has left.

    viser closes a departed viewer's buffer first and calls the page's disconnect
    callbacks after; a frame drawn in between wrote to that viewer, and viser warned
    on stderr ("Queued a ... on a closed connection"). Closing a tab is not an error:
    those writes are dropped with the connection, as viser drops a removal on a
    closed connection.
    """
    with contextlib.ExitStack() as stack:
        for client in clients:  # viser 1.1.1's own scope for writes that may find it closed
            stack.enter_context(client._websock_connection.get_message_buffer()
                                .sanctioned_dead_writes())
        yield


def wake_on_loop(server: viser.ViserServer) -> None:
    """Make every message buffer of ``server`` wake its senders on viser's loop only.

    Call once, right after creating the server (viewers that connected already
    are covered too). Reaches into viser 1.1.1's internals: it has no public
    call for this.
    """
    websock = server._websock_server  # no public API in viser 1.1.1
    loop = websock._broadcast_buffer.event_loop
    swapped = threading.Event()

    def swap_all() -> None:
        _swap(websock._broadcast_buffer)
        for state in tuple(websock._client_state_from_id.values()):
            _swap(state.message_buffer)
        swapped.set()

    def on_connect(connection: WebsockClientConnection) -> None:
        # viser runs this on its loop, before the viewer's sender starts
        _swap(connection.get_message_buffer())

    websock.on_client_connect(on_connect)
    loop.call_soon_threadsafe(swap_all)
    if not swapped.wait(10.0):
        raise RuntimeError("viser's event loop did not answer within 10 s")
