"""One frame to each of many links at once: the loop's setpoints for a whole fleet.

Why: sent link by link, each frame numbered and checksummed by its link's encoder
(:meth:`~gcs.wire.MavlinkEncoder.restamp`), a fleet's setpoints cost the loop several
times what one compiled pass over all of them costs (:class:`~gcs.wire.EncoderBatch`;
the figures are in docs/performance.md, ``bench/gcs_tick.py``). The frames are the ones
each link would send on its own: same sequence numbers, signatures, frame listeners
(the recorder) and errors.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Sequence

import numpy as np

from gcs.link._errors import LinkError
from gcs.link._link import Link
from gcs.wire import EncoderBatch, distinct_rows

__all__ = ["Fanout"]


class Fanout:
    """Sends row ``i`` of a packed array to ``links[i]``, for a fixed list of links.

    While it sends it holds every link's send lock (links opened by one
    :class:`~gcs.link.LinkManager` share one), so no other frame of
    those links can come between numbering and sending: the vehicles see no
    gap or reordering in the GCS's sequence numbers.
    """

    def __init__(self, links: Sequence[Link]) -> None:
        self._links = tuple(links)
        outbound = [link.outbound() for link in self._links]
        self._transports = [o.transport for o in outbound]
        self._closed = [o.closed for o in outbound]
        self._listened = [o.listened for o in outbound]  # live lists
        # Taken in one global order, so two fanouts over overlapping links cannot deadlock.
        locks = {id(link.send_lock): link.send_lock for link in self._links}
        self._locks: list[threading.Lock] = [locks[k] for k in sorted(locks)]
        with contextlib.ExitStack() as held:  # the batch takes the encoders' counters
            for lock in self._locks:
                held.enter_context(lock)
            self._batch = EncoderBatch([link.encoder for link in self._links])
        self._batch.load_kernel()  # not at the first send, under every link's lock

    def send(self, packed: np.ndarray, crc_extra: int,
             only: Sequence[int] | None = None) -> dict[int, Exception]:
        """Send row ``i`` of ``packed`` (:func:`~gcs.wire._encoder.packed_rows`) to link ``i``.

        ``only``: the rows to send (distinct; all by default); the others are
        neither numbered nor sent. Returns the links that failed, by row: a
        closed link (:class:`LinkError`) or its transport's exception. Never
        raises for one link. Frame listeners run under the send locks, in
        sequence order (see :meth:`Link.add_frame_listener`).
        """
        failed: dict[int, Exception] = {}
        n = len(self._links)
        if only is None:
            rows: Sequence[int] = range(n)
        else:
            try:  # before anything is numbered
                rows = distinct_rows(only, n).tolist()
            except ValueError as exc:
                raise ValueError(f"only: {exc}") from None
        if not rows:
            return failed
        whole = len(rows) == n
        for lock in self._locks:
            lock.acquire()
        try:
            data, width, lengths = self._batch.stamp_buffer(
                packed, crc_extra) if whole else self._batch.stamp_buffer(
                packed[rows], crc_extra, rows)
            # locals, one zip and no call per frame but the send: this loop runs once per
            # vehicle and tick
            transports, closed, listened = self._transports, self._closed, self._listened
            start = 0
            for i, size in zip(rows, lengths, strict=True):
                frame = data[start:start + size]
                start += width
                if closed[i].is_set():  # numbered, never sent: closed for good
                    failed[i] = LinkError(self._links[i].sysid, "link is closed")
                    continue
                try:
                    transports[i].send(frame)
                except Exception as exc:
                    failed[i] = exc
                    continue
                if listened[i]:
                    self._links[i].sent(frame)
        finally:
            for lock in reversed(self._locks):
                lock.release()
        return failed
