"""MAVLink 2 message signing: key files and the check of incoming signatures.

A signed link signs every frame it sends and refuses every frame it receives
that is unsigned, signed with another key, or replayed (MAVLink 2 signing
spec: per-stream timestamps must increase; a new stream may lag the local
clock by at most one minute).

Key file format: the 32-byte secret, either as exactly 32 raw bytes or as 64
hexadecimal characters (surrounding whitespace and one trailing newline are
allowed). :func:`write_signing_key` creates such a file with mode 0600. An
all-zero key is refused: ArduPilot treats it as "signing disabled".

Outgoing signatures are made by pymavlink (``MAVLink.signing``); incoming ones
are checked here because pymavlink records a stream's timestamp before it
checks the signature, which lets one forged frame block the real stream.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import time
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

from gcs.common import ConfigError

__all__ = [
    "SIGNATURE_LEN",
    "SignatureCheck",
    "SignatureVerifier",
    "SigningKey",
    "load_signing_key",
    "parse_signing_key",
    "signature",
    "signing_timestamp",
    "write_signing_key",
]

SIGNATURE_LEN = 13
"""Bytes of a signed frame's trailing signature: link id, 6-byte timestamp, 6-byte hash."""

_EPOCH_2015 = 1420070400.0
_ONE_MINUTE = 60 * 100_000  # in signing timestamp units (10 us)


def signature(secret: bytes, signed_part: bytes | bytearray | memoryview) -> bytes:
    """The 6-byte signature of a frame: ``signed_part`` runs from the start marker to the
    signature's timestamp (MAVLink 2 signing: first 48 bits of SHA-256(secret + part))."""
    return hashlib.sha256(secret + bytes(signed_part)).digest()[:6]


def signing_timestamp(unix_time: float | None = None) -> int:
    """MAVLink signing timestamp: units of 10 us since 2015-01-01 00:00 UTC."""
    t = time.time() if unix_time is None else unix_time
    return max(0, int((t - _EPOCH_2015) * 100_000))


@dataclass(frozen=True, repr=False)
class SigningKey:
    """A 32-byte MAVLink 2 signing secret and where it came from."""

    secret: bytes
    source: str = "<memory>"

    def __post_init__(self) -> None:
        if len(self.secret) != 32:
            raise ValueError(f"signing key must be 32 bytes, got {len(self.secret)}")
        if not any(self.secret):
            raise ValueError("signing key is all zeros (ArduPilot reads that as signing disabled)")

    def __repr__(self) -> str:  # never print the secret
        return f"SigningKey(source={self.source!r})"


def parse_signing_key(data: bytes, source: str) -> SigningKey:
    """Key from file contents: 32 raw bytes or 64 hex characters; ConfigError otherwise."""
    if len(data) == 32:
        secret = bytes(data)
    else:
        text = data.strip()
        if len(text) != 64:
            raise ConfigError(source, "", "signing key must be 32 raw bytes or 64 hexadecimal "
                              f"characters, got {len(data)} bytes")
        try:
            secret = bytes.fromhex(text.decode("ascii"))
        except (UnicodeDecodeError, ValueError):
            raise ConfigError(source, "", "signing key of 64 characters must be hexadecimal "
                              "(0-9, a-f)") from None
    try:
        return SigningKey(secret, source)
    except ValueError as exc:
        raise ConfigError(source, "", str(exc)) from None


def load_signing_key(path: str | Path) -> SigningKey:
    """Read a key file (see module docstring); unreadable or malformed files raise ConfigError."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ConfigError(str(path), "", f"cannot read signing key ({exc.strerror})") from None
    return parse_signing_key(data, str(path))


def write_signing_key(path: str | Path, *, secret: bytes | None = None) -> SigningKey:
    """Create a new key file (64 hex characters, mode 0600); never overwrites an existing file.

    Without ``secret`` a fresh random key is drawn from the OS (``secrets``).
    """
    path = Path(path)
    key = SigningKey(secrets.token_bytes(32) if secret is None else bytes(secret), str(path))
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "w", encoding="ascii") as f:
        f.write(key.secret.hex() + "\n")
    return key


class SignatureCheck(Enum):
    """Verdict on one incoming frame of a signed link."""

    OK = "correctly signed"
    UNSIGNED = "unsigned frame on a signed link"
    BAD_SIGNATURE = "signature does not match the key"
    REPLAYED = "timestamp not newer than the stream's last one (replay)"
    STALE = "new stream more than one minute behind the local clock"

    @property
    def text(self) -> str:
        """Readable reason."""
        return self.value


class SignatureVerifier:
    """Checks signatures of incoming frames against one key, tracking per-stream timestamps.

    Not thread-safe: owned by one :class:`~gcs.wire.FrameDecoder`.
    """

    def __init__(self, key: SigningKey, *, wall_clock: Callable[[], float] = time.time) -> None:
        self._secret = key.secret
        self._wall_clock = wall_clock
        self._streams: dict[tuple[int, int, int], int] = {}
        self._latest = 0

    def check(self, frame: bytes | bytearray | memoryview, *, signed: bool, sysid: int,
              compid: int) -> SignatureCheck:
        """Verdict on a whole frame (header to signature) whose CRC is already known good."""
        if not signed:
            return SignatureCheck.UNSIGNED
        link_id = frame[-SIGNATURE_LEN]
        stamp = int.from_bytes(frame[-12:-6], "little")
        digest = signature(self._secret, frame[:-6])
        if not hmac.compare_digest(digest, bytes(frame[-6:])):
            return SignatureCheck.BAD_SIGNATURE
        stream = (link_id, sysid, compid)
        last = self._streams.get(stream)
        if last is not None:
            if stamp <= last:
                return SignatureCheck.REPLAYED
        else:
            local = max(self._latest, signing_timestamp(self._wall_clock()))
            if stamp + _ONE_MINUTE < local:
                return SignatureCheck.STALE
        self._streams[stream] = stamp
        self._latest = max(self._latest, stamp)
        return SignatureCheck.OK
