"""The largest payload the team can carry: bisection on the mass, the shares being the
geometry's (they do not depend on the mass).

Why: a condition that the payload breaks names this mass as a fix.
"""

from __future__ import annotations

from gcs.analysis._forces import chain, vertical_load
from gcs.config import Team

__all__ = ["largest_payload"]


def _carries(team: Team, mass: float, share: float, gain_lhs: float, worst_share: float) -> bool:
    """Whether every payload-bound condition holds for ``mass`` kg at ``share`` (and at
    ``worst_share``, the full-speed thrust)."""
    cfg = team.config
    c = chain(team, mass, share)
    worst = vertical_load(cfg, worst_share, mass)
    return (c.load < cfg.airframe.thrust_reference and worst < cfg.airframe.thrust_max
            and cfg.limits.bank < c.max_tilt and c.max_accel > 0.0
            and cfg.limits.accel_norm <= c.max_accel and cfg.limits.accel_axis <= c.max_axis
            and gain_lhs <= c.max_axis and c.safe_margin > 0.0)


def largest_payload(team: Team, share: float, gain_lhs: float, worst_share: float) -> float:
    """The heaviest payload, kg, for which every payload-bound condition holds with each
    vehicle carrying ``share`` of it, and ``worst_share`` within full thrust (bisection; 0
    when even a feather fails). The shares are the geometry's: they do not depend on the
    mass."""
    if not _carries(team, 1e-9, share, gain_lhs, worst_share):
        return 0.0
    cfg = team.config
    lo, hi = 0.0, cfg.airframe.thrust_max / cfg.analysis.gravity / share
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _carries(team, mid, share, gain_lhs, worst_share) else (lo, mid)
    return lo
