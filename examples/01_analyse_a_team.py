"""Build a team from its config, run the paper's worst-case analysis, compute one command.

Shows the public API of ``gcs.config`` (:func:`load_team`) and ``gcs.guidance``
(:func:`analyze`, :class:`Guidance`, :class:`MotionDemand`): the figures
``gcs analyze`` prints, read from the :class:`Analysis` object, then the
guidance the team config describes, asked for one command with every vehicle
on its desired place and at rest (about zero: nothing to correct) and one with
the forward stick held.

Run from the repository root::

    python examples/01_analyse_a_team.py [--config configs/bebop_triangle.yaml]

Exit status 0 when the analysis holds, 1 when the config breaks a condition.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from gcs.analysis import analyze
from gcs.common import shipped_config
from gcs.config import load_team
from gcs.guidance import Guidance, MotionDemand


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Worst-case analysis of a team and one "
                                     "guidance command.")
    parser.add_argument("--config", default=str(shipped_config("bebop_square.yaml")),
                        help="team config (default: the shipped bebop_square.yaml)")
    args = parser.parse_args(argv)

    team = load_team(args.config)
    a = analyze(team)
    print(f"team {a.team}: {a.vehicles} vehicles, from {team.source}")
    print(f"vertical load per vehicle      {a.vertical_load:.3f} N")
    print(f"max tilt                       {a.max_tilt:.3f} rad "
          f"({math.degrees(a.max_tilt):.1f} deg)")
    print(f"horizontal force at bank limit {a.horizontal_force:.3f} N")
    print(f"max guidance acceleration      {a.max_accel:.3f} m/s^2")
    print(f"  per axis                     {a.max_accel_axis:.3f} m/s^2")
    sign = "<=" if a.gain_lhs <= a.max_accel_axis else ">"
    print(f"gain condition (eq. max)       {a.gain_lhs:.3f} {sign} {a.max_accel_axis:.3f} m/s^2")
    for warning in a.warnings:
        print(f"warning: {warning}")
    for v in a.violations:
        print(f"violation {v.term}: {v.message}")
    print(f"ok                             {a.ok}")

    guidance = Guidance.from_team(team)
    n = team.formation.n
    at_rest = (team.formation.positions, np.zeros((n, 2)), np.zeros(n))
    u = guidance.accelerations(*at_rest, MotionDemand())
    print(f"command at rest, in shape      {np.linalg.norm(u, axis=1).max():.3e} m/s^2 (largest)")
    u = guidance.accelerations(*at_rest, MotionDemand(forward=1.0))
    print(f"command at rest, full forward  {np.linalg.norm(u, axis=1).max():.3f} m/s^2 (largest)")
    return 0 if a.ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
