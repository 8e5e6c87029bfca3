"""A simulated team flown from Python, for integration tests: :class:`SimTeam`.

Why: ``gcs fly`` plays a YAML scenario and prints one JSON line; a test wants
its own assertions, loops and faults between the steps. A :class:`SimTeam`
starts the simulator and a headless GCS in lockstep on the simulator's clock
(:class:`gcs.app.HeadlessFlight`, what ``gcs fly`` flies on) and plays one
scenario step per call (:func:`gcs.app.play_step`), so a test and a scenario
file fly the same way. In lockstep the simulated world stands still while the
test's own code runs between two calls, so every run of a seed is the same
flight, whatever the machine's load. The calls are those of
:class:`gcs.testing.Team` (``_team``), shared with real vehicles; the
simulator's own parts are here: its start and the faults.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path

from gcs.app import HeadlessFlight, parse_gusts
from gcs.config import Team as LoadedTeam
from gcs.config import load_team
from gcs.testing._team import FlightError, Team

__all__ = ["SimTeam"]

GUST_MAX_M_S = 30.0
"""Largest gust per axis the simulator takes, m/s (``sim._faults.GUST_MAX_M_S``)."""

FAULT_MAX_S = 3600.0
"""Longest timed cut or gust the simulator takes, s (``sim._faults.FAULT_MAX_S``)."""


class SimTeam(Team):
    """A simulated team and a headless GCS flying it, one call per step.

    Every call that flies blocks until it is done, in sim seconds, or raises
    :class:`FlightError` naming the step and the latest warnings; a bad argument
    is a one-line ``ValueError`` (:class:`gcs.common.ConfigError`). Close it (a
    ``with`` block, or the ``sim_team`` pytest fixture) to stop the simulator,
    the GCS and every port they opened; a test that raises closes it too.

    Args:
        config: team file (or a loaded :class:`gcs.config.Team`).
        seed: of the simulator's sensor noise and gusts: one seed, one flight.
        gusts: turbulence, the gusts' standard deviation per axis, m/s (random, 2 s
            correlation, drawn from ``seed``; None: calm). :meth:`gust` adds a steady one.
        speed: sim seconds per wall second, or ``"max"``: as fast as the machine goes.
        record: .tlog file to record the flight to (``gcs report`` reads it).
        lockstep: the GCS acknowledges every tick (repeatable); False lets the simulator
            run on its own at ``speed`` (a number), as a real team would.
        insecure: fly unsigned (``gcs fly --insecure``).
        override_analysis: fly a team that ``gcs analyze`` refuses.
        start_timeout: longest wall time the simulator may take to come up, s (about 6 s
            on a quiet machine, over a minute on a loaded one).
    """

    def __init__(self, config: str | Path | LoadedTeam, *, seed: int = 0,
                 speed: float | str = "max", record: str | Path | None = None,
                 lockstep: bool = True, insecure: bool = False,
                 override_analysis: bool = False, start_timeout: float = 300.0,
                 gusts: float | None = None) -> None:
        team = config if isinstance(config, LoadedTeam) else load_team(config)
        if insecure:
            team = team.without_signing()
        super().__init__(HeadlessFlight(
            team, speed=_speed(speed, lockstep), record=None if record is None else Path(record),
            seed=_whole(seed, "seed"), override_analysis=override_analysis, lockstep=lockstep,
            ready_timeout=start_timeout, gusts=parse_gusts(gusts)))

    # -- faults ---------------------------------------------------------------------------

    def cut_link(self, sysid: int, seconds: float | None = None) -> None:
        """Silence vehicle ``sysid``'s radio both ways from this tick on, for ``seconds`` of
        sim time (the simulator restores it then) or until :meth:`restore_link`. The
        vehicle flies its own failsafe meanwhile (HOLD, then LAND). Returns at once."""
        self._fault({"action": "cut", "sysid": self._vehicle(sysid)}
                    | ({} if seconds is None else {"seconds": _duration(seconds)}))

    def restore_link(self, sysid: int) -> None:
        """End a cut of vehicle ``sysid``'s link now."""
        self._fault({"action": "restore", "sysid": self._vehicle(sysid)})

    def kill(self, sysid: int) -> None:
        """Vehicle ``sysid`` dies now: its link and liveliness go, its motors stop."""
        self._fault({"action": "kill", "sysid": self._vehicle(sysid)})

    def gust(self, wind_ned: Sequence[float], seconds: float) -> None:
        """Add ``wind_ned`` (m/s, NED: north, east, down) to the simulator's wind, on every
        vehicle and the payload, from this tick for ``seconds`` of sim time. Returns at
        once."""
        wind = [float(w) for w in wind_ned]
        if len(wind) != 3 or not all(math.isfinite(w) and abs(w) <= GUST_MAX_M_S
                                     for w in wind):
            raise ValueError(f"gust: wind_ned must be 3 numbers within ±{GUST_MAX_M_S:g} m/s, "
                             f"got {list(wind_ned)!r}")
        self._fault({"action": "gust", "sysid": 0, "ned": wind, "seconds": _duration(seconds)})

    @property
    def endpoint(self) -> str:
        """The zenoh endpoint the simulator listens on."""
        assert self._flight.endpoint is not None, "a SimTeam starts its simulator"
        return self._flight.endpoint

    # -- helpers --------------------------------------------------------------------------

    def _fault(self, command: dict[str, object]) -> None:
        self._flying()
        answer = self._flight.control(json.dumps(command).encode())
        if answer.startswith("refused"):
            raise FlightError(f"{command['action']}: the simulator {answer}")

    def _vehicle(self, sysid: int) -> int:
        ids = self.team.formation.ids
        if isinstance(sysid, bool) or not isinstance(sysid, int) or sysid not in ids:
            raise ValueError(f"no vehicle {sysid!r} in {self.team.source} (vehicles "
                             f"{', '.join(str(i) for i in ids)})")
        return sysid


def _speed(speed: float | str, lockstep: bool) -> str:
    if speed == "max":
        if not lockstep:
            raise ValueError("speed='max' needs lockstep: a simulator running free as fast "
                             "as it can leaves the GCS behind (late ticks, stale telemetry)")
        return "max"
    if isinstance(speed, bool) or not isinstance(speed, int | float) \
            or not (math.isfinite(speed) and speed > 0):
        raise ValueError(f"speed must be a positive number or 'max', got {speed!r}")
    return f"{float(speed):g}"


def _whole(value: int, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"{name} must be a whole number >= 0, got {value!r}")
    return value


def _duration(seconds: float) -> float:
    if isinstance(seconds, bool) or not isinstance(seconds, int | float) \
            or not (math.isfinite(seconds) and 0.0 < seconds <= FAULT_MAX_S):
        raise ValueError(f"seconds must be above 0 and at most {FAULT_MAX_S:g}, "
                         f"got {seconds!r}")
    return float(seconds)
