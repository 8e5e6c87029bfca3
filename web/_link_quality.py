"""Link quality in %, as ground stations show it: the share of a vehicle's frames that arrived.

Why a window: the link's counters (:class:`gcs.link.LinkHealth`) run from the
start, so a whole flight's ratio hides a radio that is failing now. Here the
frames received and the frames missing from the sequence numbers are taken
over the last ``window`` seconds. A link whose heartbeat timed out reads 0 %:
nothing arrives, so nothing is missing from the sequence numbers either.
"""

from __future__ import annotations

import collections
import math
from collections.abc import Mapping

from gcs.link import LinkHealth

__all__ = ["LinkQuality", "received_share"]


def received_share(received: int, lost: int) -> float:
    """Frames received of those sent, % (NaN: none either way). ``lost`` below 0 (late
    frames counted back, lost before the window) counts as none lost."""
    lost = max(lost, 0)
    total = received + lost
    return 100.0 * received / total if total > 0 else math.nan


class LinkQuality:
    """Each vehicle's link quality over the last ``window`` s, from its link health.

    Args:
        window: how far back the counters are compared, s.
    """

    def __init__(self, window: float = 5.0) -> None:
        self.window = window
        self._samples: dict[int, collections.deque[tuple[float, int, int]]] = {}

    def update(self, t: float, health: Mapping[int, LinkHealth]) -> dict[int, float]:
        """Take each link's counters at time ``t`` (s, any monotonic clock); quality by id."""
        out = {}
        for vid, h in health.items():
            samples = self._samples.setdefault(vid, collections.deque())
            samples.append((t, h.frames_received, h.packets_lost))
            while len(samples) > 2 and samples[1][0] <= t - self.window:
                samples.popleft()
            t0, received0, lost0 = samples[0]
            if not h.alive:
                out[vid] = 0.0
            elif t0 < t:
                out[vid] = received_share(h.frames_received - received0, h.packets_lost - lost0)
            else:  # the first sample: the counters so far
                out[vid] = received_share(h.frames_received, h.packets_lost)
        return out
