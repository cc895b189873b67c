"""The inverse APS response as a smooth free curve: hat-function basis, fit, levels, linearity.

``ln g(v)`` (ln of the relative exposure that reads as normalised value ``v``) is piecewise
linear between knots placed at quantiles of the usable frame values; frame/event consistency
only ever sees differences ``ln g(v') - ln g(v)``, so the curve is known up to a constant,
fixed by ``ln g`` = 0 at the first knot.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "FrameLevels",
    "InverseResponse",
    "frame_levels",
    "hat_basis",
    "linear_fit",
    "place_knots",
]

_LOW_MARGIN = 0.06
"""Usable frame values start this far (normalised) above the black level: nearer black, the
frames' noise is a large share of ln g, and noise in the values flattens the fitted curve (with
it the thresholds: by a sixth on a dark scene at a margin of 0.02, by 2 % at 0.05)."""

CLIP_SHARE = 5e-4
"""Share of the frame values within two ADC steps of their highest for that to be a clip level."""

BLACK_SHARE = 5e-3
"""Share of the frame values within two ADC steps of their lowest for that to be a black level.
Where the light never fails, the darkest texture's own values look like a small pile-up: 0.07 %
of a synthetic linear recording's values lay there, 0.013 above the true black (which put the
thresholds 9 % high, held to that line). Emulated raw frames with dark places held 3.9-16 %."""

_HIGH_MARGIN = 0.02
"""Usable frame values end this far below the clip level."""


@dataclass(frozen=True)
class FrameLevels:
    """The frames' black and clip levels and the range of values the calibration trusts.

    Attributes:
        black_level: normalised value of no light (the lowest value frames pile up at, or 0).
        saturation: normalised value where frames clip (1 when no pile-up at the top).
        low: lowest usable value; ``high`` the highest.
    """

    black_level: float
    saturation: float
    low: float
    high: float


def _pile_up(values: np.ndarray, at: float, tolerance: float, share: float) -> bool:
    """True when at least ``share`` of the values sit within ``tolerance`` of ``at``."""
    return np.mean(np.abs(values - at) <= tolerance) >= share


def frame_levels(frames: np.ndarray, step: float) -> FrameLevels:
    """Black and clip levels from where the frame values pile up.

    Args:
        frames: normalised frame values (any shape).
        step: one ADC step, normalised (1 / 1023 for a 10-bit DAVIS).
    """
    values = np.asarray(frames, np.float64).ravel()
    top, bottom = float(values.max()), float(values.min())
    saturation = top if _pile_up(values, top, 2 * step, CLIP_SHARE) else 1.0
    black = bottom if _pile_up(values, bottom, 2 * step, BLACK_SHARE) else 0.0
    low = black + _LOW_MARGIN
    high = min(float(np.quantile(values, 0.999)), saturation) - _HIGH_MARGIN
    return FrameLevels(black, saturation, low, max(high, low + _HIGH_MARGIN))


def place_knots(values: np.ndarray, levels: FrameLevels, count: int, step: float) -> np.ndarray:
    """``count`` (or fewer) knots at quantiles of the usable values, at least 2 steps apart."""
    values = np.asarray(values, np.float64).ravel()
    usable = values[(values >= levels.low) & (values <= levels.high)]
    if len(usable) < count:
        return np.linspace(levels.low, levels.high, 2)
    quantiles = np.quantile(usable, np.linspace(0, 1, count))
    knots = [quantiles[0]]
    for value in quantiles[1:]:
        if value - knots[-1] >= 2 * step:
            knots.append(value)
    if len(knots) < 2:
        return np.linspace(levels.low, levels.high, 2)
    return np.asarray(knots)


def hat_basis(values: np.ndarray, knots: np.ndarray) -> np.ndarray:
    """``(N, K)`` piecewise-linear (hat) basis of ``values`` at ``knots`` (clamped outside)."""
    values = np.clip(np.asarray(values, np.float64), knots[0], knots[-1])
    index = np.clip(np.searchsorted(knots, values) - 1, 0, len(knots) - 2)
    fraction = (values - knots[index]) / (knots[index + 1] - knots[index])
    basis = np.zeros((len(values), len(knots)))
    rows = np.arange(len(values))
    basis[rows, index] = 1 - fraction
    basis[rows, index + 1] = fraction
    return basis


@dataclass(frozen=True)
class InverseResponse:
    """``ln g`` at ``knots`` (``log_exposure[0] == 0``), linear between them."""

    knots: np.ndarray
    log_exposure: np.ndarray

    def __call__(self, values: np.ndarray) -> np.ndarray:
        """``ln g`` of normalised frame values (clamped to the knots' range)."""
        return hat_basis(np.ravel(values), self.knots) @ self.log_exposure


def linear_fit(
    response: InverseResponse, black: float | None, above: float = 0.0
) -> tuple[float, float, float]:
    """How well ``ln g`` is a straight line in ``ln(v - black)``: a linear sensor's shape.

    Frame/event consistency fixes ``ln g`` only up to a common scale in weakly blurred frames,
    so a linear response (``g = slope (v - black)``) may come out as a power of one; the
    straightness, not the slope, says whether the sensor is linear.

    Args:
        response: the free inverse response.
        black: the frames' black level, or None to find the one that straightens the curve
            best (below the first knot).
        above: only the knots at or above this value count (the dark end left out).

    Returns:
        ``(black, power, rms)``: the black level, the power the free curve has in
        ``v - black`` and the RMS departure of ``ln g`` from that straight line over the knots.
    """
    kept = response.knots >= above
    knots, log_g = response.knots[kept], response.log_exposure[kept]

    def straight(level: float) -> tuple[float, float]:
        x = np.log(np.maximum(knots - level, 1e-12))
        power, offset = np.polyfit(x, log_g, 1)
        return float(power), float(np.sqrt(np.mean((power * x + offset - log_g) ** 2)))

    if black is None:
        candidates = knots[0] - np.geomspace(1e-3, max(knots[0] + 0.1, 2e-3), 60)
        black = float(min(candidates, key=lambda level: straight(level)[1]))
    power, rms = straight(black)
    return black, power, rms
