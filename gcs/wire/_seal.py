"""Authenticated zenoh payloads that are not MAVLink: clock, clock ack, truth, control.

Why: MAVLink 2 signing covers the vehicles' frames, but the simulator's clock
paces the GCS, its acks pace the simulator, its truth feeds the metrics and its
control key kills vehicles; anyone on the zenoh fabric could forge them. With
the team key both ends seal and check them, so a stranger's sample is refused.

A sealed payload is ``payload || counter (8 bytes, big-endian) || tag (16 bytes)``
with ``tag = HMAC-SHA256(key, topic NUL payload counter)[:16]``. The topic in the
tag keeps a clock sample from passing as an ack; the counter, taken from the
wall clock in nanoseconds and never repeated by one sender, must grow, so a
recorded sample replayed later is refused.
"""

from __future__ import annotations

import hashlib
import hmac
import threading
import time
from collections.abc import Callable

from gcs.wire._signing import SigningKey

__all__ = ["SEAL_OVERHEAD", "SealError", "Sealer", "Unsealer"]

_COUNTER_LEN = 8
_TAG_LEN = 16
SEAL_OVERHEAD = _COUNTER_LEN + _TAG_LEN
"""Bytes a seal adds to a payload."""


class SealError(ValueError):
    """A payload refused by :class:`Unsealer`: unsealed, forged, or replayed."""


def _tag(secret: bytes, topic: bytes, body: bytes) -> bytes:
    return hmac.new(secret, topic + b"\0" + body, hashlib.sha256).digest()[:_TAG_LEN]


class Sealer:
    """Seals the payloads one sender publishes on one topic (thread-safe).

    Without a key (signing off) payloads pass unchanged.
    """

    def __init__(self, key: SigningKey | None, topic: str, *,
                 clock_ns: Callable[[], int] = time.time_ns) -> None:
        self._secret = None if key is None else key.secret
        self._topic = topic.encode()
        self._clock_ns = clock_ns
        self._last = 0
        self._lock = threading.Lock()

    def seal(self, payload: bytes) -> bytes:
        """``payload`` with its counter and tag."""
        if self._secret is None:
            return payload
        with self._lock:
            self._last = max(self._last + 1, self._clock_ns())
            counter = self._last
        body = payload + counter.to_bytes(_COUNTER_LEN, "big")
        return body + _tag(self._secret, self._topic, body)


class Unsealer:
    """Checks the payloads of one topic (thread-safe: zenoh calls back on any thread).

    Without a key (signing off) payloads pass unchanged.
    """

    def __init__(self, key: SigningKey | None, topic: str) -> None:
        self._secret = None if key is None else key.secret
        self._topic = topic.encode()
        self._last = 0
        self._lock = threading.Lock()

    @property
    def sealed(self) -> bool:
        """True when payloads must carry a seal."""
        return self._secret is not None

    def open(self, data: bytes) -> bytes:
        """The payload inside ``data``; :class:`SealError` naming why it is refused."""
        if self._secret is None:
            return data
        if len(data) < SEAL_OVERHEAD:
            raise SealError(f"not sealed with the team key ({len(data)} bytes)")
        body, tag = data[:-_TAG_LEN], data[-_TAG_LEN:]
        if not hmac.compare_digest(tag, _tag(self._secret, self._topic, body)):
            raise SealError("not sealed with the team key (forged, or another key)")
        counter = int.from_bytes(body[-_COUNTER_LEN:], "big")
        with self._lock:
            if counter <= self._last:
                raise SealError("replayed (its counter is not newer than the last one)")
            self._last = counter
        return body[:-_COUNTER_LEN]
