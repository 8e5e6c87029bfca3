"""Standard gravity: the one value the simulator, the airframe checks and the analysis share.

Why one constant: with 9.81 m/s^2 in one and 9.80665 in the other, a hover
measured in the simulator and the analysis' prediction of it would differ by
0.03 % before any physics does.
"""

from __future__ import annotations

__all__ = ["STANDARD_GRAVITY"]

STANDARD_GRAVITY = 9.80665
"""m/s^2, the conventional value. The paper's figures do not tell the two apart: its
vertical load (0.4 + 0.4 / 3) g, printed 5.22 N, is 5.230 N with this and 5.232 N with
9.81."""
