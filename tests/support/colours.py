"""Hue, saturation and value of RGB colours, for the tests that check the scene's colours.

One helper for both: the palette rule (tests/web/test_frame.py) and the pixels
of a screenshot (tests/browser/test_live_demo.py), vectorised for the latter.
"""

from __future__ import annotations

import numpy as np


def hue_saturation_value(rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hue (degrees), saturation and value (0..1) of (..., 3) colours in 0..255."""
    c = np.asarray(rgb, dtype=float) / 255.0
    r, g, b = c[..., 0], c[..., 1], c[..., 2]
    top = c.max(axis=-1)
    span = top - c.min(axis=-1)
    safe = np.where(span > 0, span, 1.0)
    hue = np.select([top == r, top == g], [((g - b) / safe) % 6.0, (b - r) / safe + 2.0],
                    (r - g) / safe + 4.0)
    return 60.0 * hue, np.where(top > 0, span / np.where(top > 0, top, 1.0), 0.0), top


def hue_apart(hue: np.ndarray, colour: tuple[int, int, int] | np.ndarray) -> np.ndarray:
    """How far ``hue`` (degrees) is from ``colour``'s hue, 0..180 degrees."""
    (own,), _, _ = hue_saturation_value(np.array([colour]))
    return np.abs((hue - own + 180.0) % 360.0 - 180.0)
