"""Link health of one vehicle: is it alive, what is lost, what is refused, how slow.

Packet loss is read from MAVLink sequence numbers per (system, component)
stream, the way ground stations do it: a jump from 10 to 14 means 3 frames
never arrived. Refused frames are those that arrived but were not believed:
bad checksum, bad or missing signature on a signed link, or another system id.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["LinkHealth", "SequenceTracker"]


@dataclass(frozen=True)
class LinkHealth:
    """Snapshot of one link's health."""

    sysid: int
    heartbeat_age_s: float | None
    """Time since the vehicle's last HEARTBEAT, s; None if none arrived."""
    alive: bool
    """True while the heartbeat is younger than the link's heartbeat timeout."""
    frames_received: int
    """Frames accepted from the vehicle."""
    frames_sent: int
    packets_lost: int
    """Frames missing from the vehicle's sequence numbers."""
    refused_bad_crc: int
    """Candidate frames with a wrong checksum (corrupted bytes)."""
    refused_signature: int
    """Frames refused by signing: unsigned, wrongly signed or replayed."""
    refused_wrong_system: int
    """Good frames from a system id other than the vehicle's, ignored."""
    foreign_systems: tuple[int, ...]
    """System ids seen on this link that are not the vehicle's."""
    garbage_bytes: int
    """Bytes that were not part of any frame."""
    truncated: int
    """Frames cut short."""
    rtt_s: float | None
    """Latest round-trip time (COMMAND_ACK or TIMESYNC), s."""
    refused_values: int = 0
    """Telemetry messages from the vehicle refused for their values (NaN, inf, huge)."""
    refused_oversize: int = 0
    """Payloads for this link dropped unread for being too long (zenoh links)."""
    signed: bool = False
    """The link signs what it sends and refuses unsigned frames (MAVLink 2 signing)."""

    @property
    def refused(self) -> int:
        """All refused frames and messages (the page's "refused" column)."""
        return (self.refused_bad_crc + self.refused_signature + self.refused_wrong_system
                + self.refused_values + self.refused_oversize)

    @property
    def loss_ratio(self) -> float:
        """Fraction of the vehicle's frames that were lost (0 with no traffic)."""
        total = self.frames_received + self.packets_lost
        return self.packets_lost / total if total else 0.0


class SequenceTracker:
    """Counts frames missing from per-stream sequence numbers; not thread-safe.

    A frame that arrives late (a UDP radio or a sender's threads reorder them) was counted
    lost when the frames after it arrived: it is counted back, and the stream goes on from
    the newest. A step back to a number never missed (a duplicate, a sender that started
    again) counts nothing. Without this, one reordered pair would read as 255 frames lost
    (the step back taken as a wrap of the 8-bit number).
    """

    def __init__(self) -> None:
        self._last: dict[tuple[int, int], int] = {}
        self._missing: dict[tuple[int, int], set[int]] = {}
        self.lost = 0
        """Frames inferred lost so far (late arrivals counted back)."""

    def update(self, sysid: int, compid: int, seq: int) -> None:
        """Account one received frame."""
        key = (sysid, compid)
        last = self._last.get(key)
        if last is None:
            self._last[key] = seq
            self._missing[key] = set()
            return
        step = (seq - last) & 0xFF
        if step == 0:
            return  # a duplicate, not a loss
        missing = self._missing[key]
        if step >= _WINDOW:  # behind the newest
            if seq in missing:
                missing.discard(seq)
                self.lost -= 1
            return  # else a duplicate of a late one, or a sender started again (it is
            # ahead again within 128 frames; a reboot is never counted as a loss)
        self._last[key] = seq
        if step == 1 and not missing:
            return  # in order, nothing outstanding: the every-frame case
        self.lost += step - 1
        missing.update((last + k) & 0xFF for k in range(1, step))
        missing.difference_update([m for m in missing if (seq - m) & 0xFF >= _WINDOW])


_WINDOW = 128
"""A sequence number this far or further ahead of the newest (mod 256) is behind it."""
