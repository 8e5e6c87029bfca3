"""Second-order Butterworth low-pass filters for the INDI loops.

INDI needs the measured signal and the actuator/attitude state delayed by the
same filter, so every signal of one loop shares one coefficient set. Filters
run as transposed direct-form-II biquads on a state array ``z[..., 2]`` so a
whole batch of vehicles and signals lives in one preallocated array.
"""

from __future__ import annotations

import math

import numpy as np

from gcs.common import kernel

__all__ = ["biquad_reset", "biquad_step", "butterworth2"]


def butterworth2(cutoff_hz: float, sample_rate_hz: float) -> np.ndarray:
    """Coefficients ``[b0, b1, b2, a1, a2]`` of a 2nd-order low-pass (a0 normalised to 1)."""
    if not 0.0 < cutoff_hz < 0.5 * sample_rate_hz:
        raise ValueError(f"cutoff {cutoff_hz} Hz must lie between 0 and the Nyquist frequency "
                         f"{0.5 * sample_rate_hz} Hz")
    # the bilinear transform of the analogue prototype, pre-warped to the cutoff (what
    # scipy.signal.butter(2, ...) gives; not imported: scipy.signal is 0.6 s of each
    # simulator's start)
    k = math.tan(math.pi * cutoff_hz / sample_rate_hz)
    norm = 1.0 / (1.0 + math.sqrt(2.0) * k + k * k)
    b0 = k * k * norm
    return np.array([b0, 2.0 * b0, b0, 2.0 * (k * k - 1.0) * norm,
                     (1.0 - math.sqrt(2.0) * k + k * k) * norm], dtype=np.float64)


@kernel()
def biquad_step(coef: np.ndarray, z: np.ndarray, i: int, j: int, x: float) -> float:
    """Filter one new sample ``x`` of signal ``j`` of vehicle ``i``; returns the output."""
    y = coef[0] * x + z[i, j, 0]
    z[i, j, 0] = coef[1] * x - coef[3] * y + z[i, j, 1]
    z[i, j, 1] = coef[2] * x - coef[4] * y
    return y


@kernel()
def biquad_reset(coef: np.ndarray, z: np.ndarray, i: int, j: int, x: float) -> None:
    """Set the state to the steady state of a constant input ``x`` (output equals ``x``)."""
    z[i, j, 1] = (coef[2] - coef[4]) * x
    z[i, j, 0] = (coef[1] - coef[3]) * x + z[i, j, 1]
