"""Sealed zenoh payloads (clock, ack, truth, control): only the team key makes them."""

from __future__ import annotations

import pytest

from gcs.wire import SEAL_OVERHEAD, Sealer, SealError, SigningKey, Unsealer

KEY = SigningKey(bytes(range(1, 33)))
OTHER = SigningKey(bytes(range(2, 34)))


def test_a_sealed_payload_opens_once() -> None:
    seal, unseal = Sealer(KEY, "fleet/a/clock"), Unsealer(KEY, "fleet/a/clock")
    first, second = seal.seal(b"t=1"), seal.seal(b"t=2")
    assert len(first) == 3 + SEAL_OVERHEAD
    assert unseal.open(first) == b"t=1" and unseal.open(second) == b"t=2"
    with pytest.raises(SealError, match="replayed"):
        unseal.open(first)


@pytest.mark.parametrize(("sealer", "why"), [
    (Sealer(OTHER, "fleet/a/clock"), "not sealed"),       # another key
    (Sealer(KEY, "fleet/a/clock_ack"), "not sealed"),     # another topic: no ack as a clock
    (Sealer(None, "fleet/a/clock"), "not sealed"),        # a stranger's plain sample
])
def test_what_the_team_key_did_not_seal_is_refused(sealer: Sealer, why: str) -> None:
    with pytest.raises(SealError, match=why):
        Unsealer(KEY, "fleet/a/clock").open(sealer.seal(b"\x00" * 40))


def test_a_flipped_bit_is_refused() -> None:
    data = bytearray(Sealer(KEY, "k").seal(b"payload"))
    for i in range(len(data)):
        bad = bytearray(data)
        bad[i] ^= 1
        with pytest.raises(SealError):
            Unsealer(KEY, "k").open(bytes(bad))


def test_counters_grow_even_when_the_clock_does_not() -> None:
    seal = Sealer(KEY, "k", clock_ns=lambda: 5)
    unseal = Unsealer(KEY, "k")
    for _ in range(3):
        unseal.open(seal.seal(b"x"))


def test_without_a_key_payloads_pass_unchanged() -> None:
    assert Sealer(None, "k").seal(b"abc") == b"abc"
    assert Unsealer(None, "k").open(b"abc") == b"abc" and not Unsealer(None, "k").sealed
