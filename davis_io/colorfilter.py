"""Colour filter arrays: the channel each pixel sees, RGB weights per pixel, OpenCV demosaic codes.

The pattern's name reads its 2x2 tile row by row from the top-left pixel (``RGGB``: (even row,
even column) red, the two mixed sites green, (odd, odd) blue). ``W`` sites sum R, G and B
equally; monochrome pixels see Rec. 709 luminance.
"""

from __future__ import annotations

import cv2
import numpy as np

from davis_io.errors import UsageError
from davis_io.types import ColorFilter

__all__ = [
    "BAYER_PATTERNS",
    "DEVICE_COLOR_FILTERS",
    "LUMINANCE_WEIGHTS",
    "bayer_to_rgb_code",
    "filter_channels",
    "filter_weights",
    "mosaic_of",
]

LUMINANCE_WEIGHTS = np.array([0.2126, 0.7152, 0.0722], np.float32)
"""Rec. 709 weights of linear R, G, B seen by a monochrome pixel."""

DEVICE_COLOR_FILTERS = (
    ColorFilter.MONO,
    ColorFilter.RGGB,
    ColorFilter.GRBG,
    ColorFilter.GBRG,
    ColorFilter.BGGR,
    ColorFilter.RGWB,
    ColorFilter.GRBW,
    ColorFilter.WBRG,
    ColorFilter.BWGR,
)
"""The DAVIS APS ``COLOR_FILTER`` register value (libcaer's enum) -> our pattern.

libcaer names its values by the tile read clockwise from the top-left pixel (``RGBG`` = 1 is
R G / G B, our ``RGGB``); ours read it row by row."""

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


_BAYER_TO_RGB = {
    ColorFilter.RGGB: cv2.COLOR_BayerRGGB2RGB,
    ColorFilter.GRBG: cv2.COLOR_BayerGRBG2RGB,
    ColorFilter.GBRG: cv2.COLOR_BayerGBRG2RGB,
    ColorFilter.BGGR: cv2.COLOR_BayerBGGR2RGB,
}
"""Our top-left-first pattern names -> OpenCV codes giving RGB order.

OpenCV's own short names count from the second row (its ``COLOR_BayerBG2RGB`` is our ``RGGB``);
the four-letter aliases used here equal those codes and read like ours.
"""


def mosaic_of(rgb: np.ndarray, color_filter: ColorFilter) -> np.ndarray:
    """The raw mosaic behind a demosaiced ``(H, W, 3)`` RGB frame: each pixel's own channel.

    Exact for demosaicing that keeps every site's own sample and interpolates only the other
    two channels (bilinear, as OpenCV's ``COLOR_Bayer*2RGB`` and libcaer's), except on the
    outermost ring of pixels, which OpenCV copies from the ring inside it.

    Raises:
        UsageError: ``color_filter`` is monochrome or has ``W`` sites (no one channel a pixel
            sees), or ``rgb`` is not ``(H, W, 3+)``.
    """
    if rgb.ndim != 3 or rgb.shape[2] < 3:
        raise UsageError(f"a demosaiced frame is (H, W, 3), not {rgb.shape}")
    channels = filter_channels(color_filter, *rgb.shape[:2])
    if channels is None or not color_filter.is_color:
        raise UsageError(
            f"colour frames cannot be mosaiced to {color_filter.value}: give a Bayer pattern "
            f"({', '.join(c.value for c in BAYER_PATTERNS)})"
        )
    return np.take_along_axis(rgb, channels[..., None], axis=2)[..., 0]


BAYER_PATTERNS = tuple(_BAYER_TO_RGB)
"""The 2x2 Bayer patterns: one colour per pixel, demosaiced by OpenCV."""


def bayer_to_rgb_code(color_filter: ColorFilter) -> int:
    """OpenCV ``cvtColor`` code demosaicing a ``color_filter`` mosaic into RGB.

    Raises:
        UsageError: the pattern is not a 2x2 Bayer pattern (mono, or with ``W`` or non-diagonal
            green sites).
    """
    if color_filter not in _BAYER_TO_RGB:
        raise UsageError(
            f"colour filter {color_filter.value} cannot be demosaiced with OpenCV; only the "
            f"2x2 Bayer patterns {', '.join(c.value for c in _BAYER_TO_RGB)} are supported"
        )
    return _BAYER_TO_RGB[color_filter]
