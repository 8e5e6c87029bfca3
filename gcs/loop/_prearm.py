"""Checks before arming: every refusal names the vehicle and the reason.

An arm goes ahead only when the GCS can fly what it would arm:

* every vehicle is placed in the team frame: its origin is known and agrees
  (:meth:`gcs.loop._team_frame.TeamFrame.problems`) and its position is
  fresh;
* the team stands as its shape: no vehicle is farther from its place in the
  desired shape (fitted onto the team, :func:`gcs.formation.fit_shape`) than
  the analysis' safe deformation (``gcs analyze``). A team taking off out of
  shape starts with the shape-keeping terms saturated; the four ArduCopters
  whose frames disagreed scattered that way;
* no autopilot tilts farther than the config's bank limit (``limits.bank_deg``):
  ArduPilot's ``ANGLE_MAX`` (centidegrees), PX4's ``MPC_TILTMAX_AIR`` (degrees).
  With ``limits.autopilot_tilt: set`` the GCS sets it to the bank limit
  (PARAM_SET), reads it back and records it as an event instead. The simulated
  vehicles answer as PX4, but their ``MPC_TILTMAX_AIR`` bounds roll and pitch
  each, not the tilt: the same kind of bound as ``limits.bank_deg`` itself (the
  largest roll/pitch angle), so the two compare as they are
  (``gcs.link._profile_sim``). A tilt bound is the stricter: neither roll nor
  pitch exceeds the tilt.

The runtime runs :meth:`Prearm.check` on its action thread before the arm
command; :class:`PrearmError` ends the arm with every reason in one line (an
error event on the page; ``gcs fly`` exits with it). While the team is ready it
also runs :meth:`Prearm.watch` on its loop thread, about once a second: the
checks that need no traffic with the vehicles (their positions and origins as
last heard, the shape, the tilt limits already read), for the page and the
snapshot, refusing nothing.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from gcs.analysis import Analysis
from gcs.config import Team
from gcs.formation import fit_shape
from gcs.link import AutopilotProfile, LinkError
from gcs.loop._fleet import FleetState
from gcs.loop._team_frame import TeamFrame

__all__ = ["READY_CHECK_PERIOD_S", "Prearm", "PrearmError"]

READY_CHECK_PERIOD_S = 1.0
"""How often :meth:`Prearm.watch` runs the checks again while the team is ready, s of the
loop's clock."""

_TILT_SLACK_DEG = 0.01
"""A tilt limit this far above the bank limit still passes (a parameter's rounding), deg."""

Note = Callable[[str, str], None]


class PrearmError(RuntimeError):
    """The checks before arming failed; ``reasons`` one line each, naming the vehicle."""

    def __init__(self, reasons: list[str]) -> None:
        self.reasons = tuple(reasons)
        super().__init__("checks before arming failed: " + "; ".join(reasons))


class Prearm:
    """The checks an arm must pass (see the module docstring).

    Args:
        team: the loaded team (shape, bank limit, whether to set tilt limits).
        analysis: its worst-case analysis (the safe deformation).
        frame: the team frame (origins).
        profiles: autopilot profile per vehicle system id.
        note: ``note(level, text)`` for events (a tilt limit set).
    """

    def __init__(self, team: Team, analysis: Analysis, frame: TeamFrame,
                 profiles: Mapping[int, AutopilotProfile], *, note: Note | None = None) -> None:
        self.team = team
        self.analysis = analysis
        self.frame = frame
        self.ids = team.formation.ids
        self.profiles = profiles
        self._note = note if note is not None else (lambda level, text: None)
        self._watched_at = -math.inf
        self._watched: tuple[str, ...] = ()

    def check(self, read_fleet: Callable[[], FleetState], *, scale: float = 1.0) -> None:
        """Run every check; :class:`PrearmError` with all the reasons if any failed.

        Blocks (origins asked for, parameters read): run it off the loop's thread.
        ``read_fleet`` gives the team's latest state, read after the origins came.
        """
        reasons = self.problems(read_fleet, scale=scale)
        if reasons:
            raise PrearmError(reasons)

    def problems(self, read_fleet: Callable[[], FleetState], *,
                 scale: float = 1.0) -> list[str]:
        """Every failed check, one line each (empty: the team may arm)."""
        placing = self.frame.problems()
        return self._standing(placing, read_fleet(), scale) + self._tilt_limits()

    def known_problems(self, fleet: FleetState, *, scale: float = 1.0) -> list[str]:
        """The checks that need no traffic with the vehicles, on what the GCS heard already:
        origins, positions and shape of ``fleet``, and the tilt limits read so far (at an
        earlier arm, or announced by the autopilot); one line each, as :meth:`problems`
        says them. Sends nothing and never blocks: the loop's thread may call it. A tilt
        limit not read yet, or one ``limits.autopilot_tilt: set`` will set, is no
        failure here."""
        return (self._standing(self.frame.problems(ask=False), fleet, scale)
                + self._known_tilt_limits())

    def watch(self, now: float, fleet: FleetState, *, scale: float = 1.0) -> tuple[str, ...]:
        """:meth:`known_problems` again once :data:`READY_CHECK_PERIOD_S` passed since the
        last time (``now`` on the loop's clock), else what it found then."""
        if not 0.0 <= now - self._watched_at < READY_CHECK_PERIOD_S:
            self._watched = tuple(self.known_problems(fleet, scale=scale))
            self._watched_at = now
        return self._watched

    def _standing(self, placing: list[tuple[int, str]], fleet: FleetState,
                  scale: float) -> list[str]:
        """The team frame's ``placing`` problems, then positions and shape of ``fleet``."""
        reasons = [text for _vid, text in placing]
        unplaced = {vid for vid, _text in placing}
        reasons += self._positions(fleet, unplaced)
        if fleet.located:
            reasons += self._shape(fleet, scale)
        return reasons

    def _positions(self, fleet: FleetState, unplaced: set[int]) -> list[str]:
        stale_after = self.team.config.safety.stale_after
        out = []
        for vid, p, age in zip(fleet.ids, fleet.p_ned, fleet.age, strict=True):
            if vid in unplaced:
                continue  # its origin is the reason, said already
            if not np.isfinite(age):
                out.append(f"vehicle {vid}: no position (no LOCAL_POSITION_NED received)")
            elif not np.all(np.isfinite(p[:2])):
                if self.frame.offset(vid) is not None:  # else: another's origin is missing
                    out.append(f"vehicle {vid}: no position in the team frame")
            elif age > stale_after:
                out.append(f"vehicle {vid}: its position is {age:.1f} s old "
                           f"(safety.stale_after {stale_after:g} s)")
        return out

    def _shape(self, fleet: FleetState, scale: float) -> list[str]:
        """The vehicles out of their places in the desired shape, each measured against the
        shape fitted onto the others: one vehicle 1 m out of a square moves a fit onto all
        four by a quarter of that, which would name every vehicle; left out of the fit in
        turn, the farthest is named with its own 1 m."""
        desired = scale * self.team.formation.positions
        actual = fleet.p_ned[:, :2]
        bound = self.analysis.safe_deformation
        fitted = actual.copy()  # the vehicles named are left out of the fit (NaN)
        named: list[int] = []
        while True:
            ghost = fit_shape(desired, fitted)
            if ghost is None:
                break
            off = np.linalg.norm(actual - ghost, axis=1)
            off[named] = -np.inf
            worst = int(np.argmax(off))
            if off[worst] <= bound:
                break
            named.append(worst)
            fitted[worst] = np.nan
        if not named:
            return []
        ghost = fit_shape(desired, fitted)
        if ghost is None:  # fewer than two vehicles in their places: measured against all
            ghost = fit_shape(desired, actual)
        assert ghost is not None  # every vehicle is located
        return [f"vehicle {fleet.ids[i]}: {float(np.linalg.norm(actual[i] - ghost[i])):.2f} m "
                f"from its place in the team's shape, beyond the analysis' safe deformation "
                f"of {bound:.2f} m: place the vehicles as the config's shape, or check their "
                f"positions" for i in sorted(named)]

    def _tilt_limits(self) -> list[str]:
        checked = [vid for vid in self.ids if self.profiles[vid].tilt_limit_param is not None]
        if not checked:
            return []
        with ThreadPoolExecutor(max_workers=min(8, len(checked)),
                                thread_name_prefix="gcs-prearm") as pool:
            found = list(pool.map(self._tilt_limit, checked))
        return [r for r in found if r is not None]

    def _known_tilt_limits(self) -> list[str]:
        limits = self.team.config.limits
        if limits.autopilot_tilt == "set":  # the arm sets them
            return []
        out = []
        for vid in self.ids:
            tilt = self.profiles[vid].known_tilt_limit_deg()
            if tilt is not None and tilt > limits.bank_deg + _TILT_SLACK_DEG:
                out.append(self._tilt_above(vid, tilt))
        return out

    def _tilt_above(self, vid: int, tilt: float) -> str:
        bank = self.team.config.limits.bank_deg
        return (f"vehicle {vid}: its tilt limit {self.profiles[vid].tilt_limit_param} is "
                f"{tilt:g} degrees, above the config's bank limit of {bank:g} degrees "
                f"(limits.bank_deg): lower it on the autopilot, or let the GCS set it "
                f"(limits.autopilot_tilt: set)")

    def _tilt_limit(self, vid: int) -> str | None:
        """Vehicle ``vid``'s tilt limit checked (or set); the reason it fails, or None."""
        profile = self.profiles[vid]
        param = profile.tilt_limit_param
        limits = self.team.config.limits
        bank = limits.bank_deg
        try:
            tilt = profile.tilt_limit_deg()
            if tilt <= bank + _TILT_SLACK_DEG:
                return None
            if limits.autopilot_tilt != "set":
                return self._tilt_above(vid, tilt)
            back = profile.set_tilt_limit_deg(bank)
        except LinkError as exc:
            return f"vehicle {vid}: its tilt limit {param} could not be checked: {exc.what}"
        if abs(back - bank) > _TILT_SLACK_DEG:
            return (f"vehicle {vid}: {param} set to {bank:g} degrees but reads back "
                    f"{back:g} degrees")
        self._note("info", f"vehicle {vid}: tilt limit {param} set from {tilt:g} to {back:g} "
                           f"degrees (limits.bank_deg), read back")
        return None
