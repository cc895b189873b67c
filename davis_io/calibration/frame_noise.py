"""``frame_noise``: how noisy a linear frame's values are at each level, from the frames alone.

A raw APS value above the black level counts photo-electrons: its variance is their shot noise,
which grows in proportion to the signal, plus the read noise and the ADC's rounding, which do
not: ``var(v) = gain * (v - black) + floor``. In one frame the noise shows as the difference of
a pixel from the mean of its four same-colour neighbours (two pixels away, so a Bayer mosaic's
colours do not mix): white noise of variance ``s`` gives that difference a variance of
``1.25 s``, and in the smoothest places of a level the scene adds little more (a blurred frame
has many such places); what it does add grows with the square of the level, a third term of the
fit that is then dropped.

The same variances tell a tone curve from a raw frame where nothing else can: a curve that
flattens towards white squeezes the noise of its bright values, so their variance falls below
that of darker ones, which a raw value's never does (:attr:`FrameNoise.falls`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FALL_RATIO", "FrameNoise", "frame_noise"]

LEVEL_BANDS = 12
"""Bands of equal pixel count the frame levels are cut into; one variance per band."""

SMOOTH_SHARE = 0.3
"""Share of each band's pixels kept: those whose neighbourhood varies least."""

MIN_PIXELS = 200
"""Fewest smooth pixels a band needs to count."""

FALL_RATIO = 0.5
"""A band's noise variance under this share of a darker band's is a fall no raw frame has. The
emulator's tone curves fell to 0.04-0.18 of their darker bands' (an S-curve, a film curve);
raw frames, linear or with the scene's texture in their variance, never fell below 0.8."""


@dataclass(frozen=True)
class FrameNoise:
    """The frames' noise variance ``gain * (v - black) + floor``, normalised value units.

    Attributes:
        gain: variance per unit of value above black (the shot noise; 0 when none shows).
        floor: variance at the black level (read noise and rounding).
        falls: whether a level band's variance is under :data:`FALL_RATIO` of a darker band's,
            as under a tone curve and never in raw frames; None with too few bands to tell.
    """

    gain: float
    floor: float
    falls: bool | None = None

    @property
    def offset(self) -> float:
        """The value above black where shot and read noise are equal (inf without shot noise)."""
        return self.floor / self.gain if self.gain > 0 else float("inf")


def _shifted(frames: np.ndarray, rows: int, columns: int) -> np.ndarray:
    return frames[
        :, 2 + rows : frames.shape[1] - 2 + rows, 2 + columns : frames.shape[2] - 2 + columns
    ]


def frame_noise(frames: np.ndarray, black: float, saturation: float, step: float) -> FrameNoise:
    """Measure the frames' noise against their level, and whether it falls as the level rises.

    Args:
        frames: ``(F, H, W)`` normalised frame values (raw: mono or a colour mosaic).
        black: normalised black level.
        saturation: normalised value where they clip (pixels near it are left out).
        step: one ADC step, normalised (its rounding is the least variance there can be).

    Returns:
        The fitted line (meant for linear frames); gain 0 and the floor at the rounding's
        variance when the frames show no noise that grows with the signal.
    """
    rounding = step * step / 12
    bands = _band_variances(np.asarray(frames, np.float64), black, saturation, step)
    if len(bands) < 3:
        return FrameNoise(0.0, rounding)
    darker_peak = np.maximum.accumulate(bands[:-1, 1])
    falls = bool(np.any(bands[1:, 1] < FALL_RATIO * darker_peak))
    weights = 1 / np.maximum(bands[:, 1], rounding)  # each band's relative error alike
    design = np.column_stack([bands[:, 0], np.ones(len(bands)), bands[:, 0] ** 2])
    gain, floor, _texture = np.linalg.lstsq(
        design * weights[:, None], bands[:, 1] * weights, rcond=None
    )[0]
    if gain <= 0:
        return FrameNoise(0.0, max(float(np.median(bands[:, 1])), rounding), falls)
    return FrameNoise(float(gain), max(float(floor), rounding), falls)


def _band_variances(frames: np.ndarray, black: float, saturation: float, step: float):
    """``(B, 2)``: each level band's mean value above black and its noise variance."""
    centre = _shifted(frames, 0, 0)
    neighbours = [_shifted(frames, r, c) for r, c in ((-2, 0), (2, 0), (0, -2), (0, 2))]
    mean = sum(neighbours) / 4
    difference = (centre - mean).ravel()
    level = ((centre + 4 * mean) / 5).ravel() - black
    texture = (
        np.abs(neighbours[0] - neighbours[1]) + np.abs(neighbours[2] - neighbours[3])
    ).ravel()
    brightest = np.maximum.reduce([centre, *neighbours]).ravel()
    usable = brightest < saturation - 2 * step
    difference, level, texture = difference[usable], level[usable], texture[usable]
    edges = np.quantile(level, np.linspace(0, 1, LEVEL_BANDS + 1)) if len(level) else []
    bands = []
    for low, high in zip(edges[:-1], edges[1:], strict=False):
        inside = np.flatnonzero((level >= low) & (level < high))
        if len(inside) < MIN_PIXELS / SMOOTH_SHARE:
            continue
        smooth = inside[texture[inside] <= np.quantile(texture[inside], SMOOTH_SHARE)]
        kept = difference[smooth] - np.median(difference[smooth])
        spread = 1.4826 * np.median(np.abs(kept)) + step
        kept = kept[np.abs(kept) <= 3 * spread]  # the scene's edges, not noise
        bands.append((float(np.mean(level[smooth])), float(np.mean(kept**2)) / 1.25))
    return np.asarray(bands, np.float64).reshape(-1, 2)
