"""Uniform wind: constant mean plus a first-order (Ornstein-Uhlenbeck) gust.

The gust is the exact discretisation of a first-order Gauss-Markov process, so
its standard deviation and correlation time do not depend on the step size.
"""

from __future__ import annotations

import numpy as np

from gcs.common import kernel

__all__ = ["gust_step"]


@kernel()
def gust_step(gust_ned: np.ndarray, decay: float, drive: float, noise: np.ndarray) -> None:
    """Advance the gust velocity (3,) in place by one step with unit normal ``noise`` (3,)."""
    for k in range(3):
        gust_ned[k] = decay * gust_ned[k] + drive * noise[k]
