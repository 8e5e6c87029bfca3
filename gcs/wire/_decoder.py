"""MAVLink byte-stream decoding that never raises: bad input is counted and dropped.

Frames are found by their start byte and header, checked (checksum with the
message's CRC_EXTRA, then the signature on a signed link) and only then
unpacked (:mod:`gcs.wire._unpack` for scalar-only types, pymavlink for the
rest). A candidate that fails its checksum costs one byte: scanning resumes
right after its start byte, so a spurious start byte in noise never swallows
the real frame behind it.

Two modes: a *stream* (serial, TCP) keeps an incomplete tail for the next
chunk; a *datagram* source (UDP, zenoh) delivers whole frames per payload, so
an incomplete tail is a truncated frame and is dropped at once.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from gcs.wire._crc import frame_crc
from gcs.wire._dialect import MavMessage, mavlink
from gcs.wire._signing import SIGNATURE_LEN, SignatureCheck, SignatureVerifier, SigningKey
from gcs.wire._unpack import HEADER_V2, unpack_v2

__all__ = ["DecodeStats", "FrameDecoder"]

_MAGIC_V2 = 0xFD
_MAGIC_V1 = 0xFE
_HEADER_V1 = 6
_IFLAG_SIGNED = 0x01
_MSG_MAP = mavlink.mavlink_map


@dataclass(frozen=True)
class DecodeStats:
    """Counters of one decoder since it was made (a snapshot)."""

    frames: int
    """Frames accepted and decoded."""
    bytes_received: int
    """Bytes fed in."""
    garbage_bytes: int
    """Bytes skipped while looking for a frame start."""
    bad_crc: int
    """Candidate frames whose checksum did not match (also corrupt headers)."""
    unknown_message: int
    """Well-framed frames of a message id the dialect does not know."""
    truncated: int
    """Frames cut short by the end of a datagram or by :meth:`FrameDecoder.flush`."""
    malformed: int
    """Frames with a good checksum that still could not be unpacked."""
    refused_unsigned: int
    """Unsigned frames refused by a signed link."""
    refused_bad_signature: int
    """Frames refused for a wrong, replayed or stale signature."""

    @property
    def refused_signature(self) -> int:
        """All frames refused by signing."""
        return self.refused_unsigned + self.refused_bad_signature

    @property
    def dropped(self) -> int:
        """All candidate frames dropped for any reason (garbage bytes not included)."""
        return (self.bad_crc + self.unknown_message + self.truncated + self.malformed
                + self.refused_unsigned + self.refused_bad_signature)


class FrameDecoder:
    """Turns received bytes into pymavlink messages; one per receiving link, not thread-safe.

    ``signing_key`` makes it a signed link's decoder: only frames correctly
    signed with that key pass (MAVLink 1 frames, which cannot be signed, are
    refused). Without a key, signed and unsigned frames are both accepted, as
    the MAVLink 2 signing spec asks of non-signing systems.
    """

    def __init__(self, *, datagram: bool, signing_key: SigningKey | None = None,
                 wall_clock: Callable[[], float] = time.time) -> None:
        self._datagram = datagram
        self._verifier = (SignatureVerifier(signing_key, wall_clock=wall_clock)
                          if signing_key is not None else None)
        self._unpacker = mavlink.MAVLink(None, 0, 0)
        self._tail = bytearray()
        self._frames = 0
        self._bytes = 0
        self._garbage = 0
        self._bad_crc = 0
        self._unknown = 0
        self._truncated = 0
        self._malformed = 0
        self._unsigned = 0
        self._bad_sig = 0

    @property
    def datagram(self) -> bool:
        """True if each fed chunk is self-contained (UDP, zenoh)."""
        return self._datagram

    @property
    def signed(self) -> bool:
        """True if unsigned and wrongly signed frames are refused."""
        return self._verifier is not None

    def stats(self) -> DecodeStats:
        """Snapshot of the counters."""
        return DecodeStats(
            frames=self._frames, bytes_received=self._bytes, garbage_bytes=self._garbage,
            bad_crc=self._bad_crc, unknown_message=self._unknown, truncated=self._truncated,
            malformed=self._malformed, refused_unsigned=self._unsigned,
            refused_bad_signature=self._bad_sig)

    def feed(self, data: bytes | bytearray | memoryview) -> list[MavMessage]:
        """Decode what ``data`` completes; never raises on bad input."""
        self._bytes += len(data)
        if self._datagram:
            messages, _ = self._scan(bytes(data), final=True)
            return messages
        self._tail += data
        messages, used = self._scan(self._tail, final=False)
        del self._tail[:used]
        return messages

    def flush(self) -> None:
        """Drop a pending incomplete frame of a stream (e.g. when the port closes)."""
        if self._tail:
            self._scan(self._tail, final=True)
            self._tail.clear()

    def _scan(self, buf: bytes | bytearray, *, final: bool) -> tuple[list[MavMessage], int]:
        out: list[MavMessage] = []
        n = len(buf)
        i = 0
        while i < n:
            magic = buf[i]
            if magic != _MAGIC_V2 and magic != _MAGIC_V1:
                i = self._skip_garbage(buf, i)
                continue
            v2 = magic == _MAGIC_V2
            header = HEADER_V2 if v2 else _HEADER_V1
            if n - i < header:
                if not final:
                    break
                self._truncated += 1
                i += 1
                continue
            length = buf[i + 1]
            if v2:
                flags = buf[i + 2]
                if flags & ~_IFLAG_SIGNED:
                    self._bad_crc += 1  # unknown incompatibility flag: not a frame we can read
                    i += 1
                    continue
                signed = bool(flags & _IFLAG_SIGNED)
                sysid, compid = buf[i + 5], buf[i + 6]
                msgid = buf[i + 7] | (buf[i + 8] << 8) | (buf[i + 9] << 16)
            else:
                signed = False
                sysid, compid, msgid = buf[i + 3], buf[i + 4], buf[i + 5]
            crc_end = i + header + length + 2
            end = crc_end + (SIGNATURE_LEN if signed else 0)
            if end > n:
                if not final and not _valid_frame_after(buf, i + 1):
                    break  # wait for the rest of this frame
                self._truncated += 1
                i += 1
                continue
            cls = _MSG_MAP.get(msgid)
            if cls is None:
                # Without CRC_EXTRA the checksum cannot be checked: believe the
                # framing only if another frame starts right behind it.
                plausible = _next_frame_plausible(buf, end, final=final)
                if plausible is None:
                    break
                if plausible:
                    self._unknown += 1
                    i = end
                else:
                    self._bad_crc += 1
                    i += 1
                continue
            if frame_crc(buf[i + 1:crc_end - 2], cls.crc_extra) != \
                    buf[crc_end - 2] | (buf[crc_end - 1] << 8):
                self._bad_crc += 1
                i += 1
                continue
            frame = bytearray(buf[i:end])
            i = end
            if self._verifier is not None:
                verdict = self._verifier.check(frame, signed=signed, sysid=sysid, compid=compid)
                if verdict is not SignatureCheck.OK:
                    if verdict is SignatureCheck.UNSIGNED:
                        self._unsigned += 1
                    else:
                        self._bad_sig += 1
                    continue
            try:
                msg = unpack_v2(frame, msgid=msgid, signature_len=SIGNATURE_LEN if signed
                                else 0) if v2 else None
                if msg is None:
                    msg = self._unpacker.decode(frame)
            except Exception:  # pymavlink raises several types on odd payloads
                self._malformed += 1
                continue
            if self._verifier is not None:
                msg._signed = True
                msg._link_id = frame[-SIGNATURE_LEN]
            self._frames += 1
            out.append(msg)
        return out, i

    def _skip_garbage(self, buf: bytes | bytearray, i: int) -> int:
        a = buf.find(_MAGIC_V2, i)
        b = buf.find(_MAGIC_V1, i)
        j = len(buf) if a < 0 and b < 0 else (b if a < 0 else a if b < 0 else min(a, b))
        self._garbage += j - i
        return j


def _next_frame_plausible(buf: bytes | bytearray, end: int, *, final: bool) -> bool | None:
    """Whether a frame start follows at ``end``; None if a stream must wait for more bytes."""
    n = len(buf)
    if end == n:
        return True if final else None
    if buf[end] == _MAGIC_V1:
        return True
    if buf[end] != _MAGIC_V2:
        return False
    if end + 2 < n:
        return not buf[end + 2] & ~_IFLAG_SIGNED
    return True if final else None


def _valid_frame_after(buf: bytes | bytearray, start: int) -> bool:
    """Whether a complete frame with a good checksum starts at or after ``start``.

    In a stream, bytes arrive in order: a complete frame behind an incomplete
    candidate proves the candidate was noise, so it need not hold frames back.
    """
    n = len(buf)
    j = start
    while True:
        a = buf.find(_MAGIC_V2, j)
        b = buf.find(_MAGIC_V1, j)
        j = b if a < 0 else a if b < 0 else min(a, b)
        if j < 0:
            return False
        v2 = buf[j] == _MAGIC_V2
        header = HEADER_V2 if v2 else _HEADER_V1
        if n - j >= header:
            flags = buf[j + 2] if v2 else 0
            msgid = (buf[j + 7] | (buf[j + 8] << 8) | (buf[j + 9] << 16)) if v2 else buf[j + 5]
            cls = _MSG_MAP.get(msgid)
            crc_end = j + header + buf[j + 1] + 2
            end = crc_end + (SIGNATURE_LEN if flags & _IFLAG_SIGNED else 0)
            if cls is not None and not flags & ~_IFLAG_SIGNED and end <= n and frame_crc(
                    buf[j + 1:crc_end - 2], cls.crc_extra) == \
                    buf[crc_end - 2] | (buf[crc_end - 1] << 8):
                return True
        j += 1
