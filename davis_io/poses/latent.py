"""Latent frames of one APS frame as 8-bit images for COLMAP, and how sharp they are.

The EDI runs on the frame as recorded (a colour sensor's raw mosaic, each mosaic pixel with its
own event map), in the linear domain when the response curve is known and on the normalised
image otherwise; the latent exposures are then gamma-encoded as a display shows them, whatever
the sensor's own response, and only then are the latent mosaics demosaiced for COLMAP.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from davis_io.colorfilter import bayer_to_rgb_code
from davis_io.poses.edi import edi_latent_frames
from davis_io.session import SensorCalibration
from davis_io.types import ColorFilter, Frame

__all__ = [
    "ResponseCurve",
    "calibrated_response",
    "auto_white",
    "display_encoding",
    "latent_images",
    "normalised_image",
    "sharpness",
]


@dataclass(frozen=True)
class ResponseCurve:
    """A monotone camera response tabulated as pixel value against linear exposure.

    Attributes:
        exposure: ``(K,)`` increasing linear exposure (any positive scale).
        value: ``(K,)`` non-decreasing normalised pixel value in ``[0, 1]`` at each exposure.
    """

    exposure: np.ndarray
    value: np.ndarray

    def to_linear(self, values: np.ndarray) -> np.ndarray:
        """Normalised pixel values to linear exposure (piecewise linear inverse)."""
        return np.interp(values, self.value, self.exposure)

    def to_values(self, exposure: np.ndarray) -> np.ndarray:
        """Linear exposure to normalised pixel values, clipped to the table's range."""
        return np.interp(exposure, self.exposure, self.value)


_GAMMA = 2.2
_MID_GREY = 0.18
"""The blurry frame's median exposure shows as this fraction of white (a camera's auto exposure)."""
_WHITE_PERCENTILE = 99.5
"""White is at most the blurry frame's exposure at this percentile."""


def calibrated_response(calibration: SensorCalibration) -> ResponseCurve | None:
    """The inverse response a calibration measured, over all of ``[0, 1]``; None without one.

    Between the black level and the first measured value the response is taken as linear
    (exposure proportional to ``v - black``); above the last, ln exposure goes on with its
    last slope. Values at or below the black level read no light.
    """
    values = np.asarray(calibration.response_value, np.float64)
    log_exposure = np.asarray(calibration.response_log_exposure, np.float64)
    if len(values) < 2:
        return None
    black = min(calibration.black_level, values[0] - 1e-3)
    below = np.linspace(black, values[0], 8)[1:-1]
    exposure_below = np.exp(log_exposure[0]) * (below - black) / (values[0] - black)
    slope = (log_exposure[-1] - log_exposure[-2]) / (values[-1] - values[-2])
    above = np.linspace(values[-1], 1.0, 4)[1:] if values[-1] < 1.0 else np.zeros(0)
    exposure_above = np.exp(log_exposure[-1] + slope * (above - values[-1]))
    return ResponseCurve(
        exposure=np.concatenate([[0.0], exposure_below, np.exp(log_exposure), exposure_above]),
        value=np.concatenate([[black], below, values, above]),
    )


def normalised_image(frame: Frame) -> np.ndarray:
    """The frame's image as float64 in ``[0, 1]`` (full scale ``2**bit_depth - 1``)."""
    return np.asarray(frame.image, np.float64) / float(2**frame.bit_depth - 1)


def _to_8bit(image: np.ndarray, color_filter: ColorFilter) -> np.ndarray:
    codes = np.clip(np.rint(image * 255.0), 0, 255).astype(np.uint8)
    if not color_filter.is_color:
        return codes
    return cv2.cvtColor(codes, bayer_to_rgb_code(color_filter))


def latent_images(
    frame: Frame,
    counts: np.ndarray,
    weights: np.ndarray,
    threshold: float,
    color_filter: ColorFilter,
    response: ResponseCurve | None = None,
) -> list[np.ndarray]:
    """The b+1 EDI latent frames of ``frame`` as 8-bit images (RGB when colour).

    Args:
        frame: the blurry APS frame (monochrome or raw mosaic).
        counts: ``(b, H, W)`` calibrated event counts of its exposure.
        weights: ``(b+1,)`` trapezoid weights.
        threshold: contrast threshold, natural-log units per event.
        color_filter: the sensor's colour filter.
        response: the response curve, or None to deblur the normalised values directly.

    Returns:
        ``b+1`` images ``(H, W)`` uint8, or ``(H, W, 3)`` uint8 RGB for Bayer sensors.
    """
    blurry = normalised_image(frame)
    if response is None:
        latent = edi_latent_frames(blurry, counts, weights, threshold)
    else:
        exposure = response.to_linear(blurry)
        linear = edi_latent_frames(exposure, counts, weights, threshold)
        latent = display_encoding(linear, auto_white(exposure))
    return [_to_8bit(image, color_filter) for image in latent]


def auto_white(exposure: np.ndarray) -> float:
    """The exposure a display shows as white: the median at mid-grey, highlights let clip.

    A scene lit from near dark to glare would otherwise be shown for its lamps, with the rest
    near black; at most the bright percentile, so a frame without highlights is not clipped.
    """
    median, bright = np.percentile(exposure, [50.0, _WHITE_PERCENTILE])
    return float(min(median / _MID_GREY, bright))


def display_encoding(linear: np.ndarray, white: float) -> np.ndarray:
    """Linear exposure as a display would show it: ``(linear / white) ** (1 / 2.2)`` in [0, 1].

    Feature detection wants the same image whatever the camera's response: a raw DAVIS frame
    is linear, so mid-grey reads a tenth of full scale and SIFT finds little in it; through the
    gamma of a display every sensor's latent frames look alike.
    """
    return np.clip(np.maximum(linear, 0.0) / max(white, 1e-12), 0.0, 1.0) ** (1 / _GAMMA)


def sharpness(image: np.ndarray) -> float:
    """Variance of the Laplacian of the (grey) image: larger is sharper."""
    grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    return float(cv2.Laplacian(grey.astype(np.float32), cv2.CV_32F).var())
