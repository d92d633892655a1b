"""The guard of every relative error in magtact (docs/method.md §5, §8).

A ratio a / b is evaluated only where |b| exceeds a fraction of the largest |b|: near a zero of
b (γ_r at θ = 0, a force at t = 0) a relative error says nothing about the model.
"""

from __future__ import annotations

import numpy as np

#: The fraction of max |b| below which a ratio a / b is not evaluated.
RELATIVE_FLOOR = 0.05


def above_floor(b, scale=None, floor: float = RELATIVE_FLOOR) -> np.ndarray:
    """Mask of the points where |b| > ``floor`` · ``scale`` (default scale: max |b|)."""
    b = np.abs(np.asarray(b, dtype=float))
    if scale is None:
        scale = np.nanmax(b) if b.size else 0.0
    return b > floor * scale
