"""Emulated sensor images through the colour filter (APS and DVS pixels share the same filter).

Which channel or weights each pixel sees comes from :mod:`davis_io.colorfilter`.
"""

from __future__ import annotations

import numpy as np

from davis_io.colorfilter import LUMINANCE_WEIGHTS
from davis_io.types import ColorFilter

__all__ = ["sensor_channels", "through_filter"]


def through_filter(radiance: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Single-channel sensor image ``(..., H, W)`` from RGB radiance ``(..., H, W, 3)``."""
    return np.einsum("...c,...c->...", radiance, weights)


def sensor_channels(radiance: np.ndarray, color_filter: ColorFilter) -> np.ndarray:
    """Full-resolution truth channels: RGB ``(..., 3)`` if colour, luminance ``(..., 1)`` if not."""
    if color_filter.is_color:
        return np.asarray(radiance, np.float32)
    return np.einsum("...c,c->...", np.asarray(radiance, np.float32), LUMINANCE_WEIGHTS)[..., None]
