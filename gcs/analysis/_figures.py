"""How a figure is printed in a message or the report: short, and a bound on its safe side.

Why one place: a violation names the value that fixes it, and the report shows the
same figure; both must print it alike (and never 300 digits for 1e300).
"""

from __future__ import annotations

import math

__all__ = ["floor3", "fmt"]


def fmt(x: float, digits: int = 3) -> str:
    """A number in a message: ``digits`` decimals, or 4 significant digits (%g) when it is
    too large for that to stay short (1e300 would print 300 digits)."""
    return f"{x:.{digits}f}" if abs(x) < 1e5 else f"{x:.4g}"


def floor3(x: float) -> str:
    """A bound printed to 3 decimals on its safe side (rounded down); %g beyond 1e5."""
    if not abs(x) < 1e5:
        return fmt(x)
    return f"{math.floor(x * 1000.0) / 1000.0:.3f}"
