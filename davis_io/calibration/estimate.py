"""``calibrate_frames``: the sensor's thresholds, latency, levels and response from a recording.

The pure estimator takes frames and events as arrays (:func:`calibrate_frames`); the session
shell (:func:`calibrate_session`) reads them, runs it and stores the result.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from davis_io.calibration.consistency import (
    KNOTS,
    ConsistencyProblem,
    fit_pixel_factors,
    fit_thresholds,
)
from davis_io.calibration.dead_time import dead_time_us
from davis_io.calibration.frame_noise import frame_noise
from davis_io.calibration.pixel_events import event_path, pixel_events
from davis_io.calibration.response_fit import (
    FrameLevels,
    frame_levels,
    linear_fit,
    place_knots,
)
from davis_io.calibration.scale import common_scale
from davis_io.errors import UsageError
from davis_io.session.calibration import SensorCalibration

__all__ = ["CalibrationInput", "LATENCIES_US", "calibrate_frames"]

LATENCIES_US = (0, 1000, 2000, 3000, 4000, 6000, 8000, 12000)
"""Event latencies tried, µs; the best is refined between its neighbours."""

LATENCY_ROUNDS = (2, 1)
"""Factor rounds after each latency profile. The first profile is taken at thresholds fitted at
latency 0, which can be far off, and is then nearly flat: corridor-s16's disagreement moved by
0.6 % over the grid at ON 0.38, OFF 0.10 (true 0.48, 0.19) and named 7.0 ms. Profiled again at
the refined thresholds it moved by 6 % and named 5.5 ms (true 2.6), the thresholds came within
2 % (4.5 % after one profile), and the events' share of the true ln change per bin, read as a
fit reads them, rose from 0.64 to 0.74 (0.88 with the true values)."""

SUBSET_PIXELS = 8_000
"""Pixels the global fits (thresholds, latency) use; every pixel gets its own factors."""

LINEAR_RMS = 0.03
"""A response is linear when the free curve departs from a straight line in ln(v - black) by
less than this RMS (ln units)."""

Progress = Callable[[str], None]


@dataclass(frozen=True)
class CalibrationInput:
    """A recording as the estimator reads it.

    Attributes:
        frames: ``(F, H, W)`` normalised frame values in [0, 1].
        adc_step: one ADC step, normalised (1 / 1023 for 10 bits).
        times_us: ``(N,)`` event times, sorted; ``x``, ``y`` pixel, ``is_on`` polarity.
        exposure_start_us: ``(F,)`` exposure starts; ``exposure_end_us`` their ends.
    """

    frames: np.ndarray
    adc_step: float
    times_us: np.ndarray
    x: np.ndarray
    y: np.ndarray
    is_on: np.ndarray
    exposure_start_us: np.ndarray
    exposure_end_us: np.ndarray

    @property
    def shape(self) -> tuple[int, int]:
        """Sensor ``(height, width)``."""
        return self.frames.shape[1], self.frames.shape[2]


class _Problems:
    """Builds consistency problems over a set of pixels at any latency (the paths built once)."""

    def __init__(self, recording: CalibrationInput, pixels: np.ndarray, levels, knots):
        height, width = recording.shape
        lookup = np.full(height * width, -1, np.int64)
        lookup[pixels] = np.arange(len(pixels))
        index = lookup[recording.y.astype(np.int64) * width + recording.x]
        chosen = index >= 0
        self._path = event_path(
            recording.times_us[chosen], index[chosen], recording.is_on[chosen], len(pixels)
        )
        self._recording = recording
        values = recording.frames.reshape(len(recording.frames), -1)[:, pixels]
        inside = (values > levels.low) & (values < levels.high)
        self.values, self.usable = values, inside[:-1] & inside[1:]
        self.knots, self.pixels = knots, pixels

    def at(self, latency_us: int, factors=None) -> ConsistencyProblem:
        """The problem of these pixels with events moved ``latency_us`` earlier.

        ``factors``: every sensor pixel's ON and OFF factors (flat), or None for ones.
        """
        events = pixel_events(
            self._path,
            self._recording.exposure_start_us,
            self._recording.exposure_end_us,
            latency_us,
        )
        on, off = (
            (np.ones(len(self.pixels)), np.ones(len(self.pixels)))
            if factors is None
            else (factors[0][self.pixels].copy(), factors[1][self.pixels].copy())
        )
        return ConsistencyProblem(
            events, self.values, self.usable, self.knots, on, off, latency_us=latency_us
        )


def _best_latency(
    problems: _Problems, theta: np.ndarray, factors: tuple[np.ndarray, np.ndarray], progress
) -> int:
    costs = []
    for latency in LATENCIES_US:
        costs.append(problems.at(latency, factors).disagreement(*theta))
        progress(f"latency {latency / 1000:g} ms: disagreement {costs[-1]:.4f} events²")
    best = int(np.argmin(costs))
    if 0 < best < len(costs) - 1:  # the parabola's vertex through the best and its neighbours
        x = np.asarray(LATENCIES_US[best - 1 : best + 2], np.float64)
        y = np.asarray(costs[best - 1 : best + 2])
        a, b, _ = np.polyfit(x, y, 2)
        if a > 0:
            return int(round(np.clip(-b / (2 * a), x[0], x[2])))
    return int(LATENCIES_US[best])


def _fit_with_factors(subset: _Problems, every: ConsistencyProblem, theta, rounds, progress):
    """Alternate every pixel's factors and the thresholds on the subset; the subset's problem."""
    problem = subset.at(every.latency_us, (every.factor_on, every.factor_off))
    theta, _, _ = fit_thresholds(problem, theta)
    for _round in range(rounds):
        _, response = problem.solve(*theta)
        theta = fit_pixel_factors(every, theta, response)
        problem.factor_on = every.factor_on[subset.pixels]
        problem.factor_off = every.factor_off[subset.pixels]
        theta, _, _ = fit_thresholds(problem, theta)
        progress(f"thresholds with pixel factors: ON {theta[0]:.3f}, OFF {theta[1]:.3f}")
    return theta, problem


def _split_half_spread(recording, subset: _Problems, every, theta, levels) -> np.ndarray:
    """Half the difference of the thresholds two disjoint halves of the pixels give."""
    halves = []
    for pixels in (subset.pixels[0::2], subset.pixels[1::2]):
        half = _Problems(recording, pixels, levels, subset.knots)
        problem = half.at(every.latency_us, (every.factor_on, every.factor_off))
        halves.append(fit_thresholds(problem, theta, tolerance=1e-4)[0])
    return 0.5 * np.abs(halves[0] - halves[1])


def _choose_pixels(recording: CalibrationInput, levels: FrameLevels, seed: int) -> np.ndarray:
    values = recording.frames.reshape(len(recording.frames), -1)
    inside = (values > levels.low) & (values < levels.high)
    candidates = np.flatnonzero((inside[:-1] & inside[1:]).sum(axis=0) >= 2)
    if len(candidates) == 0:
        raise UsageError(
            "no pixel has two consecutive frames that are neither black nor clipped: the "
            "sensor cannot be calibrated from this recording; record a scene with mid-tones, "
            "or give the thresholds (--threshold)"
        )
    rng = np.random.default_rng(seed)
    return np.sort(rng.choice(candidates, min(SUBSET_PIXELS, len(candidates)), replace=False))


def calibrate_frames(
    recording: CalibrationInput, *, seed: int = 0, progress: Progress | None = None
) -> SensorCalibration:
    """Measure the sensor from its frames and events.

    Raises:
        UsageError: fewer than two frames, or no usable pixel.
    """
    progress = progress or (lambda _line: None)
    if len(recording.frames) < 2:
        raise UsageError("calibration needs at least two frames; record longer")
    levels = frame_levels(recording.frames, recording.adc_step)
    knots = place_knots(recording.frames, levels, KNOTS, recording.adc_step)
    height, width = recording.shape
    subset = _Problems(recording, _choose_pixels(recording, levels, seed), levels, knots)
    everything = _Problems(recording, np.arange(height * width), levels, knots)
    theta, _, _ = fit_thresholds(subset.at(0), (0.3, 0.3))
    every = everything.at(0)
    theta, _ = _fit_with_factors(subset, every, theta, 1, progress)
    for rounds in LATENCY_ROUNDS:
        latency = _best_latency(subset, theta, (every.factor_on, every.factor_off), progress)
        every = everything.at(latency, (every.factor_on, every.factor_off))
        theta, problem = _fit_with_factors(subset, every, theta, rounds, progress)
    spread = _split_half_spread(recording, subset, every, theta, levels)
    scale = common_scale(problem, theta, progress)
    theta, spread = scale.theta, np.maximum(spread, scale.theta * scale.width)
    residual, response = problem.solve(*theta)
    pile_up = levels.black_level if levels.black_level > 0 else None
    black, power, straightness = linear_fit(response, pile_up)
    is_linear = straightness < LINEAR_RMS
    progress(
        f"response {'linear' if is_linear else 'not linear'}: the free curve is a power "
        f"{power:.2f} of v - {black:.3f} to {straightness:.3f} RMS"
    )
    dead_time = dead_time_us(recording.times_us, recording.x, recording.y, width)
    progress(f"pixel dead time {dead_time} µs")
    black_level = levels.black_level or (black if is_linear else 0.0)
    noise = (
        frame_noise(recording.frames, black_level, levels.saturation, recording.adc_step)
        if is_linear
        else None
    )
    if noise:
        progress(
            f"frame noise: variance {noise.gain:.2e} x (v - black) + {noise.floor:.2e} "
            f"(shot noise equals read noise {noise.offset:.4f} above black)"
        )
    return SensorCalibration(
        threshold_on=float(theta[0]),
        threshold_off=float(theta[1]),
        threshold_on_sd=float(spread[0]),
        threshold_off_sd=float(spread[1]),
        latency_us=latency,
        black_level=black_level,
        saturation=levels.saturation,
        response_linear=bool(is_linear),
        dead_time_us=dead_time,
        noise_gain=noise.gain if noise else 0.0,
        noise_floor=noise.floor if noise else 0.0,
        response_value=response.knots,
        response_log_exposure=response.log_exposure,
        pixel_factor_on=every.factor_on.reshape(height, width).astype(np.float32),
        pixel_factor_off=every.factor_off.reshape(height, width).astype(np.float32),
        residual_events=float(np.sqrt(np.mean(residual**2)) / (0.5 * theta.sum())),
        pairs=problem.pairs,
        source="measured" if scale.measured else "measured ratio, nominal scale",
        method="frame/event consistency of consecutive exposures (blur integral, free "
        "inverse response, per-pixel factors), latency profiled, the common scale "
        f"{'pinned by the blur' if scale.measured else 'nominal: the blur does not pin it'}; "
        "uncertainty: split-half spread over the pixels (and the profile's width where the "
        "scale is nominal); dead time: 1st percentile of a pixel's event intervals"
        + (
            "; frame noise: same-colour neighbours in the smoothest places of each level"
            if noise
            else ""
        ),
    )
