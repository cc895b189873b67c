"""The APS pixel: exposure integral over sub-frames, sensor noise, response curve, ADC quantisation.

A frame is made as the paper's synthetic data were (supplementary B.1), at the sensor's own pixel
sites: the single-channel radiance each pixel sees (through its colour filter) is rendered at S
sub-frame times spread evenly over the exposure, both ends included; their trapezoid-weighted sum
is the blurred radiance; ``x = gain * exposure_s * blurred`` is the exposure-normalised signal;
optional shot and read noise act on ``x`` in electrons; the response curve maps it to [0, 1];
the ADC rounds to ``2**bit_depth - 1`` levels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from davis_io.emulator.response import Response, apply_response
from davis_io.errors import UsageError

__all__ = [
    "ApsSettings",
    "expose",
    "integrate_exposure",
    "quantise",
    "sensor_noise",
    "subframe_times",
    "trapezoid_weights",
]


@dataclass(frozen=True)
class ApsSettings:
    """How the APS turns radiance into ADC values.

    Attributes:
        response: the response curve or its name (see :mod:`davis_io.emulator.response`).
        gain_per_s: multiplies radiance * exposure_s before the curve (1 / training exposure).
        bit_depth: ADC bits (10 on DAVIS).
        electrons_per_unit: photo-electrons collected at ``x = 1`` (sets shot noise); 0 turns
            shot and read noise off.
        read_noise_e: RMS read noise in electrons.
    """

    response: str | Response = "reinhard_gamma"
    gain_per_s: float = 1 / 0.15
    bit_depth: int = 10
    electrons_per_unit: float = 3000.0
    read_noise_e: float = 4.0


def trapezoid_weights(count: int) -> np.ndarray:
    """Trapezoid-rule weights of ``count`` evenly spaced samples: ends half weight, sum 1."""
    if count < 2:
        raise UsageError(f"an exposure needs at least 2 sub-frames, got {count}")
    weights = np.ones(count)
    weights[[0, -1]] = 0.5
    return weights / (count - 1)


def subframe_times(start_us: int, end_us: int, count: int) -> np.ndarray:
    """``count`` int64 µs times from ``start_us`` to ``end_us`` inclusive, evenly spaced."""
    if end_us <= start_us:
        raise UsageError(f"exposure window {start_us}..{end_us} µs is empty")
    fraction = np.arange(count) / (count - 1)
    return start_us + np.round(fraction * (end_us - start_us)).astype(np.int64)


def integrate_exposure(subframes: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Blurred radiance: ``sum_i weights[i] * subframes[i]`` over the first axis (float64)."""
    subframes = np.asarray(subframes)
    if subframes.shape[0] != len(weights):
        raise UsageError(f"{subframes.shape[0]} sub-frames but {len(weights)} weights")
    return np.tensordot(np.asarray(weights, np.float64), subframes, axes=(0, 0))


def sensor_noise(
    x: np.ndarray, electrons_per_unit: float, read_noise_e: float, rng: np.random.Generator
) -> np.ndarray:
    """Signal ``x`` with Poisson shot noise and Gaussian read noise, in the same units."""
    electrons = rng.poisson(np.maximum(x, 0) * electrons_per_unit).astype(np.float64)
    electrons += rng.normal(0.0, read_noise_e, size=electrons.shape)
    return np.maximum(electrons, 0) / electrons_per_unit


def linear_noise(response: Response, settings: ApsSettings) -> dict:
    """The noise of ``response``'s frame values when it is ``linear``: ``{"gain", "floor"}``.

    The value's variance is ``gain * (v - black) + floor``: shot noise ``k / electrons_per_unit``
    per unit of value (``k`` the response's slope times its gain), read noise
    ``(k * read_noise_e / electrons_per_unit)^2`` and the ADC's rounding ``step^2 / 12``. Empty
    for the other families (their noise is not a line in the value).
    """
    if response.family != "linear":
        return {}
    step = 1.0 / ((1 << settings.bit_depth) - 1)
    per_unit = response.slope * response.gain
    electrons = settings.electrons_per_unit
    if electrons <= 0:
        return {"gain": 0.0, "floor": step * step / 12}
    read = per_unit * settings.read_noise_e / electrons
    return {"gain": per_unit / electrons, "floor": read * read + step * step / 12}


def quantise(values: np.ndarray, bit_depth: int) -> np.ndarray:
    """ADC values: ``round(clip(values, 0, 1) * (2**bit_depth - 1))`` as uint16."""
    top = (1 << bit_depth) - 1
    return np.round(np.clip(values, 0, 1) * top).astype(np.uint16)


def expose(
    subframes: np.ndarray,
    exposure_s: float,
    settings: ApsSettings,
    rng: np.random.Generator | None,
    weights: np.ndarray | None = None,
) -> np.ndarray:
    """One APS frame from single-channel sub-frame radiance ``(S, H, W)``.

    Args:
        subframes: radiance seen by each pixel at S times of the exposure.
        exposure_s: exposure duration in seconds.
        settings: response, gain, bit depth and noise.
        rng: noise generator, or None for a noise-free frame.
        weights: ``(S,)`` integral weights summing to 1, or None for S evenly spaced times
            (:func:`trapezoid_weights`).

    Returns:
        ``(H, W)`` uint16 ADC values.
    """
    if weights is None:
        weights = trapezoid_weights(len(subframes))
    blurred = integrate_exposure(subframes, weights)
    x = settings.gain_per_s * exposure_s * blurred
    if rng is not None and settings.electrons_per_unit > 0:
        x = sensor_noise(x, settings.electrons_per_unit, settings.read_noise_e, rng)
    return quantise(apply_response(settings.response, x), settings.bit_depth)
