"""The share of the payload each vehicle carries, as the analysis designs for it.

* the static load at the desired shape: where the payload hangs under the team's
  rope lengths, which ropes are slack, each rope's tension (eq. T is the largest:
  ``(M g / n) l / sqrt(l^2 - r^2)`` when the payload hangs under the centroid of a
  regular team) and each vehicle's share of the payload;
* the design share: the larger of the paper's assumption (1/(n - 1), a third for
  four vehicles; ``analysis.payload_share``) and the largest share at rest. The
  paper's square keeps its third (a quarter at rest), a kite with two slack ropes
  gets the half its two taut ropes carry; the worst share instead where nothing is
  known to keep the split at it (:func:`split_unheld`);
* the share with the payload accelerating with the team at ``limits.accel_norm`` in
  any direction: its ropes then hold ``M (g - a)``, more of it on the side it
  accelerates towards;
* the worst share with the vehicles anywhere within ``analysis.position_error`` of
  their places (ropes that give by ``analysis.hold_stiffness``, as the simulator's
  position holds do), over every scale flown.

The geometry is :mod:`gcs.analysis._team_load`'s; this module gathers its figures for
the certificate.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from gcs.analysis._certificate import StaticShares
from gcs.analysis._forces import vertical_load
from gcs.analysis._team_load import (
    WorstLoad,
    accelerating_share,
    desired_load,
    even_rope_lengths,
    worst_load,
)
from gcs.config import Team

__all__ = ["SHARED_ROPES_CHECKED", "accel_keeping_design", "accel_keeping_share",
           "designed_for_worst", "desired_shares", "flown_shares", "no_shares", "rest_ropes",
           "split_unheld", "worst_flown_load"]

SHARED_ROPES_CHECKED = 6
"""The most taut ropes on which load sharing is checked in the simulator to hold the
payload's split within the design share (the hexagon)."""


def desired_shares(team: Team, assumed: float) -> tuple[StaticShares | None, str | None]:
    """The static load at the desired shape (None and why when the ropes cannot hang it)."""
    cfg = team.config
    lengths = cfg.payload.lengths(team.formation.n)
    try:
        at_rest = desired_load(team)
    except ValueError as exc:
        return None, str(exc)
    taut = tuple(bool(t) for t in at_rest.taut)
    offset = (float(at_rest.payload_ned[0]), float(at_rest.payload_ned[1]))
    even = None
    if not all(taut) or math.hypot(*offset) > 1e-3 * min(lengths):
        even = tuple(float(x) for x in even_rope_lengths(team))
    share = float(at_rest.share.max())
    return StaticShares(
        rope_lengths=tuple(lengths), taut=taut,
        tension=tuple(float(x) for x in at_rest.tension),
        vertical=tuple(float(x) for x in at_rest.vertical),
        horizontal=tuple(float(x) for x in at_rest.horizontal),
        share=tuple(float(x) for x in at_rest.share), payload_offset=offset,
        hang_depth=float(at_rest.payload_ned[2]), determinate=sum(taut) <= 3,
        assumed_share=assumed, worst_share=share,
        worst_vehicle=team.formation.ids[int(np.argmax(at_rest.share))],
        position_error=0.0, hold_stiffness=cfg.analysis.hold_stiffness,
        worst_tension=float(at_rest.tension.max()),
        worst_horizontal=float(at_rest.horizontal.max()),
        worst_vertical_load=vertical_load(cfg, share, cfg.payload.mass),
        design_share=max(assumed, share), even_rope_lengths=even), None


def no_shares(lengths: tuple[float, ...], assumed: float) -> StaticShares:
    """The static load of ropes that cannot hang the payload: nothing known."""
    n = len(lengths)
    nan = (math.nan,) * n
    return StaticShares(rope_lengths=lengths, taut=(False,) * n, tension=nan, vertical=nan,
                        horizontal=nan, share=nan, payload_offset=(math.nan, math.nan),
                        hang_depth=math.nan, determinate=False, assumed_share=assumed,
                        worst_share=math.nan, worst_vehicle=0, position_error=math.nan,
                        hold_stiffness=math.nan, worst_tension=math.nan,
                        worst_horizontal=math.nan, worst_vertical_load=math.nan,
                        design_share=assumed, even_rope_lengths=None)


def rest_ropes(ld: StaticShares | None) -> tuple[float, float]:
    """Eq. T at the desired shape: the largest rope tension, N, and the largest angle of a
    taut rope from vertical, rad (both inf when the ropes cannot hang the payload)."""
    if ld is None:
        return math.inf, math.inf
    return max(ld.tension), max(math.atan2(h, v) for h, v, t in
                                zip(ld.horizontal, ld.vertical, ld.taut, strict=True) if t)


def flown_shares(team: Team, ld: StaticShares, flown: tuple[float, ...]) -> StaticShares:
    """``ld`` with its worst and accelerating shares over the shapes of the scales
    ``flown`` (the smallest has the steepest ropes, the largest leans them most: their
    loads bound every shape flown with the payload)."""
    cfg = team.config
    ids = team.formation.ids
    worst = worst_flown_load(team, flown)
    accelerating = accelerating_share(team, cfg.limits.accel_norm, flown)
    return dataclasses.replace(
        ld, worst_share=worst.share, worst_vehicle=ids[worst.vehicle],
        position_error=worst.error, worst_tension=worst.tension,
        worst_horizontal=worst.horizontal,
        worst_vertical_load=vertical_load(cfg, worst.share, cfg.payload.mass),
        accel=accelerating.accel, accel_share=accelerating.share,
        accel_vehicle=ids[accelerating.vehicle], accel_tension=accelerating.tension)


def designed_for_worst(team: Team, ld: StaticShares) -> StaticShares:
    """``ld`` designed for its worst share where nothing is known to keep the split at the
    design share (:func:`split_unheld`), with why in ``design_basis``; else ``ld``."""
    unheld = split_unheld(team, ld)
    if unheld is None or ld.worst_share <= ld.design_share:
        return ld
    return dataclasses.replace(ld, design_share=ld.worst_share, design_basis=unheld)


def worst_flown_load(team: Team, scales: tuple[float, ...]) -> WorstLoad:
    """The worst load within ``analysis.position_error`` over the shapes of ``scales``: the
    largest share, tension and pull of them."""
    cfg = team.config.analysis
    worst = [worst_load(team, cfg.position_error, stiffness=cfg.hold_stiffness, scale=s)
             for s in scales]
    top = max(worst, key=lambda w: w.share)
    return dataclasses.replace(top, tension=max(w.tension for w in worst),
                               horizontal=max(w.horizontal for w in worst),
                               tried=sum(w.tried for w in worst))


def split_unheld(team: Team, ld: StaticShares) -> str | None:
    """Why nothing keeps the payload's split at the design share, or None when load
    sharing does (or three ropes or fewer fix it). Four or more taut ropes split it by
    fractions of a millimetre of the shape: without load sharing the paper's square flew
    one vehicle at 0.37 of it. Load sharing is checked in the simulator to hold teams of
    up to :data:`SHARED_ROPES_CHECKED` taut ropes within their design share (the
    hexagon's six at 0.251 of the payload); on twelve (a ring of twelve, eight ropes taut
    at rest) one vehicle flew 0.29 of it against a design 0.193, and with the shape bent
    0.7 m ropes went slack and one carried 0.72."""
    taut = sum(ld.taut)
    if ld.determinate:
        return None
    if not team.config.flight.load_sharing:
        return (f"flight.load_sharing is off: {taut} taut ropes split the payload by "
                f"fractions of a millimetre of the shape (the paper's square flew one "
                f"vehicle at 0.37 of it)")
    if taut > SHARED_ROPES_CHECKED:
        return (f"load sharing is checked to hold the design share on up to "
                f"{SHARED_ROPES_CHECKED} taut ropes, and this team hangs the payload from "
                f"{taut} (a ring of twelve flew one vehicle at 0.29 of it against a design "
                f"0.193)")
    return None


def accel_keeping_share(team: Team, share: float, accel: float, guess: float,
                        scales: tuple[float, ...] = (1.0,)) -> float:
    """The largest acceleration below ``accel`` that loads no vehicle beyond ``share`` at
    any of ``scales``, to 1/1000 of ``accel``, searched from ``guess`` (the share's linear
    estimate); 0 where even a tenth of ``accel`` does (then no limit is worth naming)."""
    def keeps(a: float) -> bool:  # the smallest scale loads one vehicle most
        return accelerating_share(team, a, (min(scales),)).share <= share

    if guess <= 0.0:  # already beyond the share at rest
        return 0.0
    if keeps(guess):
        low, high = guess, accel  # ``accel`` itself loads one vehicle beyond it
    else:
        low, high = 0.1 * accel, guess
        if not keeps(low):
            return 0.0
    while high - low > 1e-3 * accel:  # bisection: the share grows with the acceleration
        mid = 0.5 * (low + high)
        low, high = (mid, high) if keeps(mid) else (low, mid)
    return low


def accel_keeping_design(team: Team, ld: StaticShares, scales: tuple[float, ...]) -> float:
    """The acceleration limit that keeps the accelerating share of ``ld`` within its design
    share at ``scales`` (0: none worth naming), searched from the share's linear estimate
    between rest and ``ld.accel``."""
    rest = max(ld.share)
    guess = ld.accel * (ld.design_share - rest) / max(ld.accel_share - rest, 1e-12)
    return accel_keeping_share(team, ld.design_share, ld.accel, guess, scales)
