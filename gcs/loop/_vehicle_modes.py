"""Each vehicle's flight mode against the one the GCS's setpoints need.

Every autopilot profile names its streaming mode (the one that flies the GCS's
setpoints) and its landing modes. A vehicle out of its streaming mode is either
coming down on its own (the team lands with it) or waiting to be re-engaged.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from gcs.link import AutopilotProfile
from gcs.loop._events import EventLog
from gcs.loop._fleet import FleetState
from gcs.loop._phases import Phase

__all__ = ["COMING_DOWN_DROP_M", "VehicleModes"]

COMING_DOWN_DROP_M = 0.5
"""How far below the team's median altitude a vehicle out of its streaming mode counts as
coming down on its own, m (the load-sharing trims move a vehicle a few cm)."""

_KEEP_MODE = frozenset({Phase.LIFTING, Phase.FORMATION, Phase.SETTING_DOWN})
"""Phases in which a vehicle leaving its streaming mode is a warning, not news."""


class VehicleModes:
    """The team's streaming and landing modes, in the team's order; and the mode changes
    seen, reported as events."""

    def __init__(self, profiles: Sequence[AutopilotProfile]) -> None:
        self.streaming = tuple(p.streaming_mode for p in profiles)
        """Each vehicle's mode that flies the GCS's setpoints."""
        self._landing = tuple(p.landing_modes for p in profiles)
        self._modes: dict[int, str] = {}
        self._seen: tuple[str, ...] | None = None

    def coming_down(self, fleet: FleetState) -> np.ndarray:
        """(n,) True where a vehicle is disarmed, in one of its profile's landing modes, or
        out of its streaming mode and more than :data:`COMING_DOWN_DROP_M` below the
        team's median altitude. The last: a mode whose descent is the pilot's (ArduCopter
        SITL switched to LOITER with no transmitter's throttle falls to the ground), which
        the team holding above it would otherwise learn of only when it disarmed."""
        down = ~fleet.armed | np.array([m in landing for m, landing in zip(
            fleet.modes, self._landing, strict=True)], dtype=bool)
        alt = -fleet.p_ned[:, 2]
        if np.count_nonzero(np.isfinite(alt)) >= 2:
            out = np.array([m != want for m, want in zip(
                fleet.modes, self.streaming, strict=True)], dtype=bool)
            down |= out & (alt < float(np.nanmedian(alt)) - COMING_DOWN_DROP_M)
        return down

    def out_flying(self, ids: Sequence[int], modes: Sequence[str],
                   coming_down: np.ndarray) -> tuple[int, ...]:
        """The vehicles out of their streaming mode that are not coming down: those to
        re-engage."""
        return tuple(vid for vid, mode, want, down in zip(
            ids, modes, self.streaming, coming_down, strict=True)
            if mode != want and not down)

    def report(self, fleet: FleetState, phase: Phase, events: EventLog) -> None:
        """Say every mode change since the last call: a warning where a vehicle left its
        streaming mode while carrying (from lifting on), news otherwise."""
        if fleet.modes == self._seen:  # one comparison on most ticks, not one per vehicle
            return
        self._seen = fleet.modes
        for vid, mode, streaming in zip(fleet.ids, fleet.modes, self.streaming, strict=True):
            before = self._modes.get(vid)
            self._modes[vid] = mode
            if before is not None and mode != before:
                level = "warning" if phase in _KEEP_MODE and mode != streaming else "info"
                events.add(level, f"vehicle {vid}: mode {mode} (was {before})")
