"""The wording of what the analysis warns of: what a team can fly but should know, and
the config that would change it.

A warning is not a violation: the team is still certified. It says what the geometry
shows that the paper's fixed share does not (slack ropes, a vehicle that can carry more
than its design share), what the sticks cannot do, and where the analysis departs from
the config (a scale not flown); with the config that designs for it where one does.
The figures a warning names are computed by the maths modules, and only when the
warning is given.
"""

from __future__ import annotations

import math

from gcs.analysis._certificate import StaticShares
from gcs.analysis._figures import floor3, fmt
from gcs.analysis._forces import chain, vertical_load
from gcs.analysis._scales import SmallestScale
from gcs.analysis._shares import accel_keeping_design
from gcs.config import Team, TeamConfig

__all__ = ["distance_error_warnings", "load_warnings", "motion_warnings", "rope_angle_warnings",
           "scale_min_warnings"]


def motion_warnings(unavailable: tuple[str, ...], mu_r: float) -> list[str]:
    """What the sticks cannot do for a team whose vehicles have one edge each (a pair)."""
    out = []
    sticks = [stick for motion, stick in (("translate_x", "forward"), ("translate_y", "right"))
              if motion in unavailable]
    if sticks:
        out.append(f"each vehicle has one edge, so the team moves along it only, never "
                   f"sideways to it: the {' and '.join(sticks)} stick"
                   f"{'s do' if len(sticks) > 1 else ' does'} nothing")
    if "rotate" in unavailable and mu_r > 0:
        out.append(f"the team cannot spin (each vehicle has one edge): "
                   f"guidance.max_rotation_disagreement {mu_r:g} has no effect")
    return out


def scale_min_warnings(team: Team, smallest: SmallestScale) -> list[str]:
    """``guidance.scale_min`` raised in flight: why, and what flies the configured one."""
    cfg = team.config
    low = cfg.guidance.scale_min
    if not smallest.scale > low:
        return []
    share = smallest.share_at_scale_min
    load = vertical_load(cfg, share, cfg.payload.mass)
    what = (f"accelerating at limits.accel_norm {cfg.limits.accel_norm:g} m/s^2 puts "
            f"{share:.3f} of the payload on one vehicle: a vertical load of {fmt(load, 2)} N "
            f"not below the reference thrust {fmt(cfg.airframe.thrust_reference, 2)} N (85 % "
            f"of full thrust)" if math.isfinite(share) else "the ropes cannot hang the payload")
    return [f"the GCS flies scales from {smallest.scale:g}, not guidance.scale_min {low:g}: "
            f"at {low:g}, {what}; guidance.scale_min at least {smallest.scale:g} says so in "
            f"the config"]


def load_warnings(team: Team, ld: StaticShares, scales: tuple[float, ...]) -> list[str]:
    """What the geometry says that the paper's fixed share does not (``scales``: those
    flown)."""
    out = []
    if ld.even_rope_lengths is not None:
        out.append(_uneven_warning(team, ld, ld.even_rope_lengths))
    if ld.worst_share > ld.design_share + 1e-3:
        out.append(_worst_share_warning(team, ld))
    if ld.accel_share > ld.design_share + 1e-3:
        out.append(_accel_warning(team, ld, scales))
    if ld.design_basis:
        out.append(f"{ld.design_basis}: the analysis designs for the worst share "
                   f"{ld.worst_share:.3f}")
    return out


def rope_angle_warnings(design_angle: float, rest_angle: float) -> list[str]:
    """The design rope angle below the nominal shape's: eq. Th designs for less pull than
    the team hangs the payload with."""
    if not design_angle < rest_angle:
        return []
    return [f"the design rope angle {fmt(design_angle)} rad is below the rope angle of the "
            f"nominal shape {fmt(rest_angle)} rad"]


def distance_error_warnings(distance_error: float, safe: float) -> list[str]:
    """Eq. max's distance error beyond the safe deformation ``safe``."""
    if not distance_error > safe > 0:
        return []
    return [f"eq. max assumes distance errors up to {fmt(distance_error, 2)} m, beyond the "
            f"safe deformation of {fmt(safe)} m"]


def _lengths_text(lengths: tuple[float, ...], configured: tuple[float, ...]) -> str:
    """``lengths`` to the mm, or finer where that would print a length that differs from
    its configured one as the same (positions rounded to a tenth of a mm leave a ring's
    ropes micrometres from taut)."""
    digits = 3
    while digits < 6 and any(abs(a - b) > 0.5e-6 and f"{a:.{digits}f}" == f"{b:.{digits}f}"
                             for a, b in zip(lengths, configured, strict=True)):
        digits += 1
    return ", ".join(f"{x:.{digits}f}" for x in lengths)


def _uneven_warning(team: Team, ld: StaticShares, even: tuple[float, ...]) -> str:
    """Slack ropes or a payload off the centroid at the desired shape: the shares, and the
    rope lengths ``even`` that hang it under the centroid with every rope taut."""
    ids = team.formation.ids
    slack = [str(i) for i, t in zip(ids, ld.taut, strict=True) if not t]
    carry = ", ".join(f"{i} {s:.3f}" for i, s, t in zip(ids, ld.share, ld.taut, strict=True)
                      if t)
    head = (f"at the desired shape the ropes of vehicles {', '.join(slack)} are slack"
            if slack else "at the desired shape the payload hangs "
            f"{math.hypot(*ld.payload_offset):.3f} m off the centroid")
    return (f"{head}: shares of the payload {carry}; ropes of "
            f"[{_lengths_text(even, ld.rope_lengths)}] m (payload.rope_lengths, in the order "
            f"of vehicles) hang it under the centroid with every rope taut")


def _worst_share_warning(team: Team, ld: StaticShares) -> str:
    """A vehicle off its place can carry more than the design share: its load, and the
    payload share that designs for it."""
    return (f"with the vehicles up to {ld.position_error:g} m off their places "
            f"(analysis.position_error) vehicle {ld.worst_vehicle} can carry "
            f"{ld.worst_share:.3f} of the payload ({sum(ld.taut)} taut ropes"
            f"{' share it statically indeterminately' if not ld.determinate else ''}), "
            f"where the analysis designs for {ld.design_share:.3f}: a vertical load of "
            f"{fmt(ld.worst_vertical_load, 2)} N{_beyond(team.config, ld.worst_vertical_load)}"
            f", {_accel_left(team, ld.worst_share)}; "
            f"analysis.payload_share: {_designing_share(ld.worst_share)} designs for it")


def _accel_warning(team: Team, ld: StaticShares, scales: tuple[float, ...]) -> str:
    """The payload accelerating at the guidance's limit loads a vehicle beyond the design
    share: by how much, and the acceleration limit that keeps it within."""
    cfg = team.config
    fix = accel_keeping_design(team, ld, scales)
    load = vertical_load(cfg, ld.accel_share, cfg.payload.mass)
    axis = (f" (and limits.accel_axis, now {cfg.limits.accel_axis:g})"
            if cfg.limits.accel_axis > fix else "")
    named = (f"limits.accel_norm at most {floor3(fix)}{axis} keeps it within the design share"
             if fix >= 0.1 * ld.accel else
             f"analysis.payload_share: {_designing_share(ld.accel_share)} "
             f"designs for it (any acceleration loads it beyond the share at rest)")
    return (f"with the payload accelerating at limits.accel_norm {ld.accel:g} m/s^2 vehicle "
            f"{ld.accel_vehicle} carries {ld.accel_share:.3f} of it, "
            f"where the analysis designs for {ld.design_share:.3f}: a vertical load of "
            f"{fmt(load, 2)} N{_beyond(cfg, load)}, {_accel_left(team, ld.accel_share)}; "
            f"{named}")


def _beyond(cfg: TeamConfig, load: float) -> str:
    """The reference thrust named when ``load`` is not below it."""
    return (f", above the reference thrust {fmt(cfg.airframe.thrust_reference, 2)} N"
            if load >= cfg.airframe.thrust_reference else "")


def _accel_left(team: Team, share: float) -> str:
    """The guidance acceleration the force chain leaves with ``share`` of the payload on
    one vehicle."""
    left = chain(team, team.config.payload.mass, share).max_accel
    return (f"{fmt(left)} m/s^2 of guidance acceleration left" if left > 0.0
            else "no guidance acceleration left")


def _designing_share(share: float) -> int:
    """The ``analysis.payload_share`` that designs for ``share`` of the payload."""
    return max(1, math.floor(1.0 / share + 1e-9))
