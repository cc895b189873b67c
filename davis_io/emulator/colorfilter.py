"""What each sensor pixel sees through the colour filter: one channel, or luminance if monochrome.

The pattern's name reads its 2x2 tile row by row from the top-left pixel (``RGGB``: (even row,
even column) red, the two mixed sites green, (odd, odd) blue). ``W`` sites sum R, G and B
equally; monochrome pixels see Rec. 709 luminance. APS and DVS pixels share the same filter.
"""

from __future__ import annotations

import numpy as np

from davis_io.types import ColorFilter

__all__ = [
    "LUMINANCE_WEIGHTS",
    "filter_channels",
    "filter_weights",
    "sensor_channels",
    "through_filter",
]

LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722], np.float32)
"""Rec. 709 weights of linear R, G, B seen by a monochrome pixel."""

_LETTER_WEIGHTS = {
    "R": np.array([1, 0, 0], np.float32),
    "G": np.array([0, 1, 0], np.float32),
    "B": np.array([0, 0, 1], np.float32),
    "W": np.full(3, 1 / 3, np.float32),
}


def filter_weights(color_filter: ColorFilter, height: int, width: int) -> np.ndarray:
    """``(H, W, 3)`` float32 weights of linear R, G, B summed by each pixel."""
    if color_filter is ColorFilter.MONO:
        return np.broadcast_to(LUMINANCE_WEIGHTS, (height, width, 3)).copy()
    tile = np.stack([_LETTER_WEIGHTS[letter] for letter in color_filter.value])
    site = (np.arange(height)[:, None] % 2) * 2 + np.arange(width)[None, :] % 2
    return tile[site]


def filter_channels(color_filter: ColorFilter, height: int, width: int) -> np.ndarray | None:
    """``(H, W)`` int64 channel each pixel sees: 0, 1, 2 for R, G, B, 3 for luminance (mono).

    Returns None for patterns with ``W`` sites, which sum channels (use :func:`filter_weights`).
    """
    if color_filter is ColorFilter.MONO:
        return np.full((height, width), 3, np.int64)
    if "W" in color_filter.value:
        return None
    tile = np.array(["RGB".index(letter) for letter in color_filter.value], np.int64)
    return tile[(np.arange(height)[:, None] % 2) * 2 + np.arange(width)[None, :] % 2]


def through_filter(radiance: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Single-channel sensor image ``(..., H, W)`` from RGB radiance ``(..., H, W, 3)``."""
    return np.einsum("...c,...c->...", radiance, weights)


def sensor_channels(radiance: np.ndarray, color_filter: ColorFilter) -> np.ndarray:
    """Full-resolution truth channels: RGB ``(..., 3)`` if colour, luminance ``(..., 1)`` if not."""
    if color_filter.is_color:
        return np.asarray(radiance, np.float32)
    return np.einsum("...c,c->...", np.asarray(radiance, np.float32), LUMINANCE_WEIGHTS)[..., None]
