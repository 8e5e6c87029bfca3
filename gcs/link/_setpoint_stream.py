"""A team's setpoint stream: the loop hands over accelerations, the link layer does the rest.

One call per tick (:meth:`SetpointStream.send`) with the team's horizontal
accelerations and each vehicle's altitude target. Here, not in the loop: each
autopilot's vertical channel (:meth:`AutopilotProfile.vertical_setpoint`), packing
the whole fleet at once (:class:`~gcs.wire.SetpointPacker`), numbering, signing
and sending in one batch (:class:`~gcs.link.Fanout`), the gaps between rounds, and
the re-sends between ticks (:meth:`SetpointStream.resend_while`): the guidance stays
at 4 Hz while a vehicle's 0.5 s setpoint timeout never sees a late tick.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Sequence

import numpy as np

from gcs.link._errors import LinkError
from gcs.link._fanout import Fanout
from gcs.link._profile import AutopilotProfile
from gcs.wire import SETPOINT_MESSAGE, SetpointPacker

__all__ = ["Refresh", "SetpointStream", "Unsent"]

Unsent = Callable[[int, str], None]
"""Told ``(vehicle id, reason)`` of every setpoint that was not sent."""

Refresh = Callable[[], "tuple[np.ndarray, np.ndarray] | None"]
"""What a re-send sends: ``(accel (n, 2), altitude targets (n,) z NED)``; None: nothing."""


class SetpointStream:
    """The setpoints of a fixed team of vehicles, in the loop's order of ``profiles``.

    Args:
        profiles: one autopilot profile per vehicle, in the team's order.
        clock: the loop's clock (the vehicles' setpoint timeouts run on it).
        on_unsent: told of every setpoint not sent, and why; never raised.
        gap_s: time on ``clock`` between two rounds after which the vehicles may have
            dropped to hold (:meth:`take_gap`).
    """

    def __init__(self, profiles: Sequence[AutopilotProfile], *, clock: Callable[[], float],
                 on_unsent: Unsent, gap_s: float) -> None:
        self._ids = tuple(p.link.sysid for p in profiles)
        # one call per round and vehicle only where the vertical channel is not z itself
        self._vertical_calls = [(i, p.vertical_setpoint)
                                for i, p in enumerate(profiles) if not p.vertical_is_z]
        links = [p.link for p in profiles]
        targets = np.array([(link.sysid, link.target_component) for link in links]).reshape(-1, 2)
        self._packer = SetpointPacker(
            target_system=targets[:, 0], target_component=targets[:, 1],
            kind=np.array([p.setpoint_kind.type_mask for p in profiles]),
            boot_time=np.array([link.boot_time for link in links]))
        self._fanout = Fanout(links)
        self._clock = clock
        self._on_unsent = on_unsent
        self._gap_s = gap_s
        self._lock = threading.Lock()  # the loop and the re-send thread share the packer
        self._last_wall = -math.inf  # wall time of the last round (-inf: none)
        self._last = -math.inf  # the same on the loop's clock
        self._gap_max = 0.0
        self._gap_seen = False
        self.resends = 0
        """Rounds re-sent between ticks so far."""

    @property
    def gap_max(self) -> float:
        """Longest time between two rounds of one stream so far, s of the loop's clock."""
        return self._gap_max

    @property
    def last_round(self) -> float:
        """The loop's time of the last round (-inf: the stream is stopped)."""
        return self._last

    def take_gap(self) -> bool:
        """Whether a round came more than ``gap_s`` after the one before since the last
        call (the vehicles may have dropped to hold)."""
        seen, self._gap_seen = self._gap_seen, False
        return seen

    def stop(self) -> None:
        """No setpoints now: the next round starts a new stream (no gap to measure)."""
        self._last_wall = self._last = -math.inf

    def send(self, accel: np.ndarray, altitude_z: np.ndarray) -> None:
        """One round: vehicle ``i`` gets ``accel[i]`` (NED m/s^2, finite) and its vertical
        channel for the altitude target ``altitude_z[i]`` (z NED, m).

        A setpoint that cannot be sent (a target not finite, a profile's refusal,
        a closed link) is reported through ``on_unsent`` and never raised.
        """
        vertical = np.array(altitude_z, dtype=float)
        bad: list[int] = []
        if not np.isfinite(vertical).all():  # never reaches a vehicle, whatever its profile
            bad = np.flatnonzero(~np.isfinite(vertical)).tolist()
            for i in bad:
                self._unsent(i, f"altitude target not finite: {vertical[i]}")
            if len(bad) == len(vertical):
                return
        only = self._vertical_from_profiles(vertical, refused=bad)
        with self._lock:
            wall, now = time.monotonic(), self._clock()
            gap = now - self._last  # inf: the first round of a stream
            if math.isfinite(gap):
                self._gap_max = max(self._gap_max, gap)
                if gap > self._gap_s:
                    self._gap_seen = True
            self._last_wall, self._last = wall, now
            packed = self._packer.pack(wall, accel, vertical)
            failed = self._fanout.send(packed, SETPOINT_MESSAGE.crc_extra, only)
        for i, exc in failed.items():
            self._unsent(i, exc)

    def resend_while(self, refresh: Refresh, *, slot: float, done: threading.Event,
                     stop: threading.Event,
                     on_error: Callable[[Exception | None], None]) -> None:
        """Re-send ``refresh()`` whenever ``slot`` s of wall time passed without a round,
        until ``done`` or ``stop`` is set (a thread's target). ``on_error`` is told each
        failed re-send's exception, and None after each one that went."""
        while not (done.is_set() or stop.is_set()):
            wait = self._last_wall + slot - time.monotonic()
            if wait > 0.0:
                done.wait(wait)
                continue
            try:
                fresh = refresh()
                if fresh is not None:
                    self.send(*fresh)
                    self.resends += 1
            except Exception as exc:  # report, and keep the stream alive
                on_error(exc)
                fresh = None
            else:
                on_error(None)
            if fresh is None:
                done.wait(slot)

    def _vertical_from_profiles(self, vertical: np.ndarray, *,
                                refused: list[int]) -> list[int] | None:
        """Fill in the vertical channel of the profiles that compute it from each vehicle's
        altitude target in ``vertical``; the rows that can be sent (None: all), having
        reported why each other one cannot."""
        refused = list(refused)
        for i, vertical_setpoint in self._vertical_calls:
            if i in refused:
                continue
            try:
                value = float(vertical_setpoint(float(vertical[i])))
            except Exception as exc:
                refused.append(i)
                self._unsent(i, exc)
                continue
            if not math.isfinite(value):
                refused.append(i)
                self._unsent(i, f"vertical setpoint not finite: {value}")
                continue
            vertical[i] = value
        if not refused:
            return None
        vertical[refused] = 0.0  # packed, never sent
        return sorted(set(range(len(vertical))) - set(refused))

    def _unsent(self, i: int, why: Exception | str) -> None:
        self._on_unsent(self._ids[i], why.what if isinstance(why, LinkError) else str(why))
