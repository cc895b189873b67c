"""``calibrate_frames``: the sensor's thresholds, latency, levels and response from a recording.

The pure estimator takes frames and events as arrays (:func:`calibrate_frames`); the session
shell (:func:`calibrate_session`) reads them, runs it and stores the result.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from functools import cached_property
from itertools import takewhile

import numpy as np

from davis_io.calibration.consistency import (
    KNOTS,
    THRESHOLD_RANGE,
    ConsistencyProblem,
    fit_pixel_factors,
    fit_thresholds,
    normalise_factors,
    refine_pixel_factors,
)
from davis_io.calibration.dead_time import dead_time_us
from davis_io.calibration.frame_noise import FrameNoise, frame_noise
from davis_io.calibration.pixel_events import event_path, pixel_events
from davis_io.calibration.plausible import (
    BLACK_LEVEL,
    DEAD_TIME_US,
    FACTOR_SPREAD,
    LATENCY_US,
    THRESHOLD,
    THRESHOLD_SCALE,
    Assumptions,
    flat_profile,
)
from davis_io.calibration.response_fit import (
    FrameLevels,
    InverseResponse,
    frame_levels,
    linear_fit,
    place_knots,
)
from davis_io.calibration.scale import CommonScale, common_scale
from davis_io.cores import usable_cores
from davis_io.errors import UsageError
from davis_io.gaps import overlapping
from davis_io.pixel_trains import pixel_order
from davis_io.session.calibration import SensorCalibration
from davis_io.session.defaults import DEFAULT_THRESHOLD

__all__ = ["CalibrationInput", "LATENCIES_US", "LONGER_LATENCIES_US", "calibrate_frames"]

LATENCIES_US = (0, 1000, 2000, 3000, 4000, 6000, 8000, 12000)
"""Event latencies tried, µs; the best is refined between its neighbours."""

LONGER_LATENCIES_US = (16000, 24000, 32000)
"""Latencies tried next, one at a time, while the best is the last one tried. A slow pixel in the
dark (an emulated pixel with a 30 Hz cut-off, upstream v2e's noisy preset) was best at 17 ms;
fitted with that instead of the 0 ms assumed at the end of the shorter profile, on the same
poses, it scored 23.2 against 22.6 dB HDR, 20.4 against 18.8 dB at novel exposures, and a log
contrast of 0.68 against 0.54. A recording at usual light stops at 12 ms: these cost it nothing."""

LATENCY_ROUNDS = (2, 1)
"""Factor rounds after each latency profile. The first profile is taken at thresholds fitted at
latency 0, which can be far off, and is then nearly flat: corridor-s16's disagreement moved by
0.6 % over the grid at ON 0.38, OFF 0.10 (true 0.48, 0.19) and named 7.0 ms. Profiled again at
the refined thresholds it moved by 6 % and named 5.5 ms (true 2.6), the thresholds came within
2 % (4.5 % after one profile), and the events' share of the true ln change per bin, read as a
fit reads them, rose from 0.64 to 0.74 (0.88 with the true values)."""

SUBSET_PAIRS = 60_000
"""Usable pairs the global fits (thresholds, latency) read: pixels are drawn until they hold as
many. Every pixel gets its own factors. On an emulated room (15 pairs a pixel) the thresholds
from two disjoint halves of 8,000 pixels differed by 0.1 %, a thirtieth of their stated
uncertainty, so 4,000 pixels measure them as well in half the time."""

MIN_EVENTS_PER_PAIR = 0.05
"""Events per pixel between consecutive frames below which the frames and events cannot measure
the thresholds, latency, factors or response. Emulated sessions hold 3 to 18; the events of one
thinned to 0.002 (2,565 in all) gave a threshold ratio, a latency and a pixel spread measured
from nothing but the frames' noise."""

SUBSET_PIXELS = 8_000
"""Pixels the global fits use at most (a recording of few or short pairs)."""

BLOCK_PIXELS = 4096
"""Pixels whose factors are fitted together. A whole DAVIS346 at once (17 M events) took 26 s
to cut into pieces, a block at a time 4 s: each block's arrays stay in the caches and in memory
already mapped."""

LINEAR_RMS = 0.03
"""A response is linear when the free curve departs from a straight line in ln(v - black) by
less than this RMS (ln units)."""

RAW_LINEAR_RMS = 0.06
""":data:`LINEAR_RMS` for frames that bear a raw ADC's two marks: values piled up at a black
level above 0 and at a clip level below full scale. Such frames are a raw reading, and their
free curve may bend more than a tone curve's noise allows: 0.037-0.045 RMS on one emulated
linear sensor of a dark scene (a DAVIS240 and a DAVIS346, with its 65 Hz pixels and with 3 kHz
ones), against 0.010-0.027 on the other linear ones measured; every tone curve measured, none
of them with a black level above 0, departed by 0.078 or more."""

DARK_END = 0.1
"""Frame values below this share of full scale are the dark end, where noise bends the free
curve."""

LINEAR_SCALE_SPREAD = 0.05
"""The thresholds' standard uncertainty, as a share, where the response is held linear: the
largest error of thresholds so fitted on the emulated linear sessions was 8.5 % (`room-s22`:
its frames' noise; then `lamp-s108` 4.9 %, `corridor-s103` 2.8 %, `corridor-s0` 0.4 %), within
two of these."""

HELD_LINEAR_AGREEMENT = np.sqrt(2)
"""Where the blur pins the thresholds' scale, the line is held only if the free curve's power
lies within this factor of 1, the scale the line implies within that of the blur's. The free
curve trades its top against the scale (linear frames' powers 0.84-1.12 measured, thresholds
as far off), but a tone curve straight in ln v (a pure gamma) has a power of 1.8 or more: the
blur's scale, not the line's, is then the measurement."""

MIN_BRIGHT_KNOTS = 4
"""Knots above the dark end a straight line through 0 is judged on at the least (frames whose
values all lie in the dark end keep the black the search found)."""

Progress = Callable[[str], None]


@dataclass(frozen=True)
class CalibrationInput:
    """A recording as the estimator reads it.

    Attributes:
        frames: ``(F, H, W)`` normalised frame values in [0, 1].
        adc_step: one ADC step, normalised (1 / 1023 for 10 bits).
        times_us: ``(N,)`` event times, sorted; ``x``, ``y`` pixel, ``is_on`` polarity.
        exposure_start_us: ``(F,)`` exposure starts; ``exposure_end_us`` their ends.
        gaps_us: ``(G, 2)`` stretches of the stream whose events were not recorded
            (:mod:`davis_io.gaps`): no pair of frames is read across one.
    """

    frames: np.ndarray
    adc_step: float
    times_us: np.ndarray
    x: np.ndarray
    y: np.ndarray
    is_on: np.ndarray
    exposure_start_us: np.ndarray
    exposure_end_us: np.ndarray
    gaps_us: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))

    def pairs(self, latency_us: int) -> np.ndarray:
        """``(F-1,)`` True for consecutive frames whose events stay clear of every gap.

        The events of a pair, read ``latency_us`` late, run from the first exposure's start to
        the second's end.
        """
        start = self.exposure_start_us[:-1] + latency_us
        end = self.exposure_end_us[1:] + latency_us
        return ~overlapping(self.gaps_us, start, end)

    @property
    def shape(self) -> tuple[int, int]:
        """Sensor ``(height, width)``."""
        return self.frames.shape[1], self.frames.shape[2]

    @cached_property
    def pixel(self) -> np.ndarray:
        """``(N,)`` int32 each event's pixel, ``y * width + x``."""
        return self.y.astype(np.int32) * self.shape[1] + self.x


class _Problems:
    """Builds consistency problems over a set of pixels at any latency (the paths built once)."""

    def __init__(
        self,
        recording: CalibrationInput,
        pixels: np.ndarray,
        levels: FrameLevels,
        knots: np.ndarray,
        pairs: np.ndarray,
        events: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    ):
        """Paths of ``pixels``' events, those given or picked from the recording.

        ``events``: the pixels' own ``(times, index among pixels, is_on)`` when already chosen.
        """
        self._events = _events_of(recording, pixels) if events is None else events
        self._path = event_path(*self._events, len(pixels))
        self._recording, self.levels = recording, levels
        values = recording.frames.reshape(len(recording.frames), -1)[:, pixels]
        inside = (values > levels.low) & (values < levels.high)
        self.values, self.usable = values, inside[:-1] & inside[1:] & pairs[:, None]
        self.knots, self.pixels, self.pair_mask = knots, pixels, pairs

    def half(self, parity: int) -> _Problems:
        """The problems of every other pixel, from the first (``parity`` 0) or the second (1)."""
        times, index, is_on = self._events
        keep = index % 2 == parity
        return _Problems(
            self._recording,
            self.pixels[parity::2],
            self.levels,
            self.knots,
            self.pair_mask,
            (times[keep], index[keep] // 2, is_on[keep]),
        )

    def at(
        self, latency_us: int, factors: tuple[np.ndarray, np.ndarray] | None = None
    ) -> ConsistencyProblem:
        """The problem of these pixels with events moved ``latency_us`` earlier.

        ``factors``: these pixels' ON and OFF factors, or None for ones.
        """
        events = pixel_events(
            self._path,
            self._recording.exposure_start_us,
            self._recording.exposure_end_us,
            latency_us,
        )
        ones = np.ones(len(self.pixels))
        on, off = (ones, ones.copy()) if factors is None else (f.copy() for f in factors)
        duration_us = self._recording.exposure_end_us - self._recording.exposure_start_us
        return ConsistencyProblem(
            events,
            self.values,
            self.usable,
            self.knots,
            on,
            off,
            np.log(np.asarray(duration_us, np.float64)),
            latency_us=latency_us,
        )


def _events_of(
    recording: CalibrationInput, pixels: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The events of ``pixels``: times, the pixel's index among them, polarity."""
    height, width = recording.shape
    lookup = np.full(height * width, -1, np.int64)
    lookup[pixels] = np.arange(len(pixels))
    index = lookup[recording.pixel]
    chosen = index >= 0
    return recording.times_us[chosen], index[chosen], recording.is_on[chosen]


def _factors(problem: ConsistencyProblem) -> tuple[np.ndarray, np.ndarray]:
    return problem.factor_on, problem.factor_off


def _best_latency(
    problems: _Problems,
    theta: np.ndarray,
    factors: tuple[np.ndarray, np.ndarray],
    grid: _LatencyGrid,
    progress,
) -> tuple[int, np.ndarray, tuple[int, ...]]:
    """The latency the disagreement is least at (refined between its neighbours), and the profile.

    Returns:
        The latency, the disagreement at each latency tried, and those latencies: the grid's
        first ones, then its longer ones while the best is the last one tried.
    """
    tried, costs = [], []

    def cost(latency: int) -> float:
        return problems.at(latency, factors).disagreement(*theta)

    def keep(latency: int, value: float) -> None:
        tried.append(latency)
        costs.append(value)
        progress(f"latency {latency / 1000:g} ms: disagreement {value:.4f} events²")

    with ThreadPoolExecutor(usable_cores()) as pool:  # numpy lets go of the interpreter
        for latency, value in zip(grid.first, pool.map(cost, grid.first), strict=True):
            keep(latency, value)
    for latency in grid.longer:
        if int(np.argmin(costs)) < len(costs) - 1:
            break
        keep(latency, cost(latency))
    costs = np.asarray(costs)
    best = int(np.argmin(costs))
    if 0 < best < len(costs) - 1:  # the parabola's vertex through the best and its neighbours
        x = np.asarray(tried[best - 1 : best + 2], np.float64)
        y = costs[best - 1 : best + 2]
        a, b, _ = np.polyfit(x, y, 2)
        if a > 0:
            return int(round(np.clip(-b / (2 * a), x[0], x[2]))), costs, tuple(tried)
    return int(tried[best]), costs, tuple(tried)


def _fit_with_factors(problem: ConsistencyProblem, theta, rounds: int, progress) -> np.ndarray:
    """Alternate the pixels' factors and the thresholds; the thresholds."""
    theta, _ = fit_thresholds(problem, theta)
    for _round in range(rounds):
        _, response = problem.solve(*theta)
        theta = fit_pixel_factors(problem, theta, response)
        theta, _ = fit_thresholds(problem, theta)
        progress(f"thresholds with pixel factors: ON {theta[0]:.3f}, OFF {theta[1]:.3f}")
    return theta


def _split_half_spread(subset: _Problems, problem: ConsistencyProblem, theta) -> np.ndarray:
    """Half the difference of the thresholds two disjoint halves of the pixels give.

    The halves are fitted side by side where two cores are usable (a pool makes no more
    threads than it is given tasks).
    """

    def fitted(parity: int) -> np.ndarray:
        factors = tuple(f[parity::2] for f in _factors(problem))
        half = subset.half(parity).at(problem.latency_us, factors)
        return fit_thresholds(half, theta, tolerance=1e-4)[0]

    with ThreadPoolExecutor(usable_cores()) as pool:
        first, second = pool.map(fitted, (0, 1))
    return 0.5 * np.abs(first - second)


def _sensor_factors(
    recording: CalibrationInput, subset: _Problems, problem: ConsistencyProblem, theta
) -> tuple[np.ndarray, np.ndarray]:
    """Every sensor pixel's ON and OFF factors at the subset's thresholds, latency and response.

    Each pixel's factors depend on its own pairs alone, so the search runs on the subset and
    every pixel is fitted once, at its end, a block of pixels at a time (a block per usable
    core at once: numpy lets go of the interpreter inside its loops).
    """
    _, response = problem.solve(*theta)

    def fitted(block: tuple[np.ndarray, tuple]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        pixels, events = block
        found = _Problems(
            recording, pixels, subset.levels, subset.knots, subset.pair_mask, events
        ).at(problem.latency_us)
        refine_pixel_factors(found, theta, response)
        return found.factor_on, found.factor_off, found.usable.sum(axis=0)

    with ThreadPoolExecutor(usable_cores()) as pool:
        factor_on, factor_off, pairs = zip(*pool.map(fitted, _pixel_blocks(recording)), strict=True)
    factors = np.concatenate(factor_on), np.concatenate(factor_off)
    normalise_factors(*factors, np.concatenate(pairs), theta)
    return factors


def _pixel_blocks(recording: CalibrationInput):
    """The sensor's pixels in blocks of :data:`BLOCK_PIXELS`, each with its own events.

    The events are put in block order once: gathering each block's from the whole stream read
    all of it again per block (3 s of 24 M events).

    Yields:
        The block's pixels and their ``(times, index among them, is_on)``.
    """
    height, width = recording.shape
    count = -(-height * width // BLOCK_PIXELS)
    block = recording.pixel // BLOCK_PIXELS
    order = pixel_order(block, count)  # each block's events in time order
    counts = np.bincount(block, minlength=count)
    del block
    times, pixel, is_on = (
        recording.times_us[order],
        recording.pixel[order],
        recording.is_on[order],
    )
    del order
    ends = np.cumsum(counts)
    for number, (begin, end) in enumerate(zip(ends - counts, ends, strict=True)):
        first = number * BLOCK_PIXELS
        pixels = np.arange(first, min(first + BLOCK_PIXELS, height * width))
        yield pixels, (times[begin:end], pixel[begin:end] - first, is_on[begin:end])


def _choose_pixels(
    recording: CalibrationInput, levels: FrameLevels, pairs: np.ndarray, seed: int
) -> np.ndarray:
    """Pixels with two usable pairs or more, drawn until they hold :data:`SUBSET_PAIRS`.

    At most :data:`SUBSET_PIXELS` of them (none: empty).
    """
    values = recording.frames.reshape(len(recording.frames), -1)
    inside = (values > levels.low) & (values < levels.high)
    usable = (inside[:-1] & inside[1:] & pairs[:, None]).sum(axis=0)
    candidates = np.flatnonzero(usable >= 2)
    drawn = np.random.default_rng(seed).permutation(candidates)
    enough = int(np.searchsorted(np.cumsum(usable[drawn]), SUBSET_PAIRS)) + 1
    return np.sort(drawn[: min(enough, SUBSET_PIXELS)])


@dataclass(frozen=True)
class _LatencyGrid:
    """The frame pairs the latency profile reads, and the latencies it may try on them.

    Attributes:
        pairs: ``(F-1,)`` the consecutive frames read.
        first: the latencies always tried.
        longer: those tried next, in turn, while the best is the last one tried.
    """

    pairs: np.ndarray
    first: tuple[int, ...]
    longer: tuple[int, ...]


def _latency_grid(recording: CalibrationInput) -> _LatencyGrid:
    """The frame pairs to read and the latencies to try, so that no pair reaches into a gap.

    The pairs usable at every latency of :data:`LATENCIES_US` while they are most of those
    usable without latency; else those, read only at the latencies that keep all of them clear
    (a recording whose events stop a few milliseconds after each exposure). Of
    :data:`LONGER_LATENCIES_US`, those up to the first that would read a pair into a gap.
    """
    pairs = recording.pairs(0)
    every = pairs.copy()
    for latency in LATENCIES_US:
        every &= recording.pairs(latency)
    if every.sum() >= 0.75 * pairs.sum():
        pairs, first = every, LATENCIES_US
    else:
        first = tuple(
            latency for latency in LATENCIES_US if np.array_equal(recording.pairs(latency), pairs)
        )
    if not first or first[-1] != LATENCIES_US[-1]:
        return _LatencyGrid(pairs, first, ())
    clear = takewhile(lambda latency: recording.pairs(latency)[pairs].all(), LONGER_LATENCIES_US)
    return _LatencyGrid(pairs, first, tuple(clear))


@dataclass
class _Consistency:
    """What frame/event consistency measured: the raw estimates, before their review."""

    theta: np.ndarray
    spread: np.ndarray
    pixel_share: np.ndarray
    scale: CommonScale
    latency_us: int
    latency_costs: np.ndarray
    latencies: tuple[int, ...]
    problem: ConsistencyProblem
    factors: tuple[np.ndarray, np.ndarray]
    residual: np.ndarray
    response: InverseResponse


def _consistency(
    recording: CalibrationInput, levels: FrameLevels, seed: int, progress
) -> _Consistency | None:
    """Thresholds, pixel factors, latency and response from the pairs of consecutive exposures.

    None when no pixel has two usable pairs (frames black or clipped, or the stream's gaps
    leave no pair of exposures with the events between them).
    """
    grid = _latency_grid(recording)
    pixels = _choose_pixels(recording, levels, grid.pairs, seed)
    if len(pixels) == 0:
        return None
    knots = place_knots(recording.frames, levels, KNOTS, recording.adc_step)
    subset = _Problems(recording, pixels, levels, knots, grid.pairs)
    problem = subset.at(0)
    theta = _fit_with_factors(problem, (0.3, 0.3), 1, progress)
    for rounds in LATENCY_ROUNDS:
        latency, costs, latencies = _best_latency(subset, theta, _factors(problem), grid, progress)
        problem = subset.at(latency, _factors(problem))
        theta = _fit_with_factors(problem, theta, rounds, progress)
    spread = _split_half_spread(subset, problem, theta)
    factors = _sensor_factors(recording, subset, problem, theta)
    scale = common_scale(problem, theta, progress)
    residual, response = problem.solve(*scale.theta)
    return _Consistency(
        theta=scale.theta,
        spread=np.maximum(spread, scale.theta * scale.width),
        pixel_share=spread / theta,
        scale=scale,
        latency_us=latency,
        latency_costs=costs,
        latencies=latencies,
        problem=problem,
        factors=factors,
        residual=residual,
        response=response,
    )


def calibrate_frames(
    recording: CalibrationInput, *, seed: int = 0, progress: Progress | None = None
) -> SensorCalibration:
    """Measure the sensor from its frames and events; assume (and say so) what cannot be.

    Raises:
        UsageError: fewer than two frames.
    """
    progress = progress or (lambda _line: None)
    if len(recording.frames) < 2:
        raise UsageError("calibration needs at least two frames; record longer")
    notes = Assumptions(progress)
    levels = frame_levels(recording.frames, recording.adc_step)
    height, width = recording.shape
    dead_time = dead_time_us(recording.times_us, recording.pixel)
    progress(f"pixel dead time {dead_time} µs")
    if not notes.check("dead_time_us", dead_time, DEAD_TIME_US, "no dead time (0)"):
        dead_time = 0
    density = len(recording.times_us) / (height * width * (len(recording.frames) - 1))
    if density < MIN_EVENTS_PER_PAIR:
        why = (
            f"too few events to measure from: {len(recording.times_us)}, "
            f"{density:.3f} per pixel between consecutive frames"
        )
        return _without_consistency(recording, levels, dead_time, why, notes)
    found = _consistency(recording, levels, seed, progress)
    if found is None:
        why = (
            "no pixel has two pairs of consecutive exposures with usable values and the events "
            "between them (frames black or clipped, or gaps in the stream)"
        )
        return _without_consistency(recording, levels, dead_time, why, notes)
    thresholds = _reviewed_thresholds(found, notes)
    latency = _reviewed_latency(found, notes)
    factor_on, factor_off = _reviewed_factors(found.factors, notes)
    black, saturation, linear_power, noise = _response(recording, found, levels, notes, progress)
    is_linear = linear_power is not None
    held = None
    if is_linear and "thresholds" not in notes:
        held = _held_linear(found, levels, black, linear_power, progress)
    theta, spread = _reviewed_scale(found, thresholds, held, notes)
    residual, log_exposure = found.residual, found.response.log_exposure
    if held is not None:
        residual, log_exposure = held.residual, held.log_exposure
    if is_linear and noise is None:
        noise = frame_noise(recording.frames, black, saturation, recording.adc_step)
    if noise:
        balance = (
            f"shot noise equals read noise {noise.offset:.4f} above black"
            if noise.gain > 0
            else "read noise alone, no shot noise measured"
        )
        progress(
            f"frame noise: variance {noise.gain:.2e} x (v - black) + {noise.floor:.2e} ({balance})"
        )
    return SensorCalibration(
        threshold_on=float(theta[0]),
        threshold_off=float(theta[1]),
        threshold_on_sd=float(spread[0]),
        threshold_off_sd=float(spread[1]),
        latency_us=latency,
        black_level=black,
        saturation=saturation,
        response_linear=is_linear,
        dead_time_us=dead_time,
        noise_gain=noise.gain if noise else 0.0,
        noise_floor=noise.floor if noise else 0.0,
        response_value=found.response.knots,
        response_log_exposure=log_exposure,
        pixel_factor_on=factor_on.reshape(height, width).astype(np.float32),
        pixel_factor_off=factor_off.reshape(height, width).astype(np.float32),
        residual_events=float(np.sqrt(np.mean(residual**2)) / (0.5 * theta.sum())),
        pairs=found.problem.pairs,
        source=_source(notes, held is not None),
        method=_METHOD
        + (f"; {_HELD_LINEAR_METHOD}" if held is not None else "")
        + (f"; frame noise: {_NOISE_METHOD}" if noise else ""),
        assumed=dict(notes.reasons),
    )


_METHOD = (
    "frame/event consistency of consecutive exposures (blur integral, free inverse response, "
    "per-pixel factors), no pair across a gap in the events, latency profiled; each estimate "
    "checked against its search's bounds and what a DAVIS can have; uncertainty: the larger of "
    "a split-half spread over the pixels and the width of the common scale's profile (or the "
    "range it cannot tell apart); dead time: 1st percentile of a pixel's event intervals"
)
_HELD_LINEAR_METHOD = (
    "linear frames: thresholds fitted again with the response held to ln(v - black), "
    f"uncertainty {LINEAR_SCALE_SPREAD:.0%} at least"
)
_NOISE_METHOD = "same-colour neighbours in the smoothest places of each level"
_NOMINAL = f"the nominal {DEFAULT_THRESHOLD} for ON and OFF, ± 50 %"


def _source(notes: Assumptions, scale_from_frames: bool) -> str:
    if "thresholds" in notes:
        return "assumed"
    if "threshold_scale" not in notes:
        return "measured"
    return f"measured ratio, {'linear frames' if scale_from_frames else 'nominal'} scale"


def _nominal() -> tuple[np.ndarray, np.ndarray]:
    """The nominal thresholds and their wide uncertainty (half their value)."""
    theta = np.array([DEFAULT_THRESHOLD, DEFAULT_THRESHOLD])
    return theta, 0.5 * theta


def _reviewed_thresholds(found: _Consistency, notes: Assumptions) -> tuple[np.ndarray, np.ndarray]:
    """The fitted thresholds, or the nominal ones where the fit ran to a bound or off range."""
    low, high = THRESHOLD_RANGE
    if min(found.theta) <= low * 1.05 or max(found.theta) >= high * 0.95:
        notes.add("thresholds", f"the fit ran to its search's bound ({low}-{high})", _NOMINAL)
        return _nominal()
    if not all(THRESHOLD.holds(float(value)) for value in found.theta):
        notes.add(
            "thresholds",
            f"ON {found.theta[0]:.3f} and OFF {found.theta[1]:.3f}: outside what a DAVIS can "
            f"have ({THRESHOLD.describe()})",
            _NOMINAL,
        )
        return _nominal()
    return found.theta, found.spread


@dataclass(frozen=True)
class _HeldLine:
    """Thresholds fitted with the response held to the line of linear frames.

    Attributes:
        theta: ``(2,)`` ON and OFF thresholds.
        residual: each usable pair's residual there (ln units).
        log_exposure: the line, ``ln(v - black)`` at the knots (0 at the first).
    """

    theta: np.ndarray
    residual: np.ndarray
    log_exposure: np.ndarray


def _held_linear(
    found: _Consistency, levels: FrameLevels, black: float, power: float, progress
) -> _HeldLine | None:
    """The thresholds fitted again with the response held to the line of linear frames.

    A free curve trades its shape against the thresholds' common scale: on emulated linear
    sessions its top bent up and the blur pinned the scale 1-14 % off (`lamp-s108` +14 %,
    `corridor-s103` -10 %); held to ``ln(v - black)``, the frames state the scale themselves
    (+4.9 % and +2.8 %), also where the frames are too sharp for the blur to pin it.

    The line is only as good as its black level. Where the frames pile up at one, it is
    measured; else it is the level that straightens the free curve best, and where the blur
    pins the scale that is the better measure: on synthetic linear frames that never go black,
    a black found at 0.020 (true 0.040) put the held thresholds 4.6 % low, the blur's 0.6 %.

    Returns:
        The thresholds and the line's fit; None where the blur pins the scale and the line
        stands on a black level that was not measured or disagrees with it
        (:data:`HELD_LINEAR_AGREEMENT`), or where the line puts them where no DAVIS has them.
    """
    if found.scale.measured and not levels.black_level > 0:
        progress("response not held linear: the blur pins the scale, the frames no black level")
        return None
    if found.scale.measured and not 1 / HELD_LINEAR_AGREEMENT < power < HELD_LINEAR_AGREEMENT:
        progress(
            f"response not held linear: the free curve's power {power:.2f} is too far from 1 "
            "for the blur's thresholds"
        )
        return None
    problem = replace(found.problem, linear_black=black)
    theta, _ = fit_thresholds(problem, found.theta / power)
    if not all(THRESHOLD.holds(float(value)) for value in theta):
        progress(f"response not held linear: it puts the thresholds at {np.round(theta, 3)}")
        return None
    progress(f"thresholds with the response held linear: ON {theta[0]:.3f}, OFF {theta[1]:.3f}")
    residual, line = problem.solve(*theta)
    return _HeldLine(theta, residual, line.log_exposure)


def _reviewed_scale(
    found: _Consistency,
    thresholds: tuple[np.ndarray, np.ndarray],
    held_linear: _HeldLine | None,
    notes: Assumptions,
) -> tuple[np.ndarray, np.ndarray]:
    """The thresholds at the linear frames' scale, else at the one the blur pins, else nominal.

    Returns:
        The thresholds and their uncertainty.
    """
    theta, spread = thresholds
    if "thresholds" in notes:
        return theta, spread
    reason = "the frames are too sharp for the blur to pin the thresholds' common scale"
    if held_linear is not None:
        if not found.scale.measured:
            instead = "the linear frames' scale, with the measured ratio"
            notes.add("threshold_scale", reason, instead)
        theta = held_linear.theta
        return theta, theta * np.maximum(found.pixel_share, LINEAR_SCALE_SPREAD)
    if not found.scale.measured:
        instead = f"the nominal {DEFAULT_THRESHOLD} with the measured ratio"
        notes.add("threshold_scale", reason, instead)
    return theta, spread


def _reviewed_latency(found: _Consistency, notes: Assumptions) -> int:
    """The profiled latency, or 0 where the profile is flat, ends at its bound or is off range."""
    instead = "no latency (0 ms)"
    if len(found.latencies) < 2 or flat_profile(found.latency_costs):
        notes.add("latency_us", "the disagreement hardly changes with it (a flat profile)", instead)
        return 0
    if len(found.latencies) > 2 and found.latency_us >= found.latencies[-1]:
        top = found.latencies[-1] / 1000
        notes.add("latency_us", f"the profile's best is its last value, {top:g} ms", instead)
        return 0
    if not notes.check("latency_us", found.latency_us, LATENCY_US, instead):
        return 0
    return found.latency_us


def _reviewed_factors(
    factors: tuple[np.ndarray, np.ndarray], notes: Assumptions
) -> tuple[np.ndarray, np.ndarray]:
    """Every pixel's ON and OFF factors, or ones where their spread says nothing was learned."""
    both = np.concatenate(factors)
    moved = both[both != 1.0]
    spread = float(np.std(moved)) if len(moved) else 0.0
    if notes.check("pixel_factors", spread, FACTOR_SPREAD, "every pixel's factor 1"):
        return factors
    return np.ones_like(factors[0]), np.ones_like(factors[1])


def _response(
    recording: CalibrationInput,
    found: _Consistency,
    levels: FrameLevels,
    notes: Assumptions,
    progress,
) -> tuple[float, float, float | None, FrameNoise | None]:
    """The frames' levels, their free curve's power if linear, and the noise measured on the way.

    The noise is that of frames taken as raw (None where none was measured). A curve fitted
    beside thresholds the fit could not measure is not measured either (the two trade against
    each other): the frames' noise alone then tells raw ones (:func:`_raw_noise`, power 1).
    Otherwise the free curve is reviewed.
    """
    if "thresholds" not in notes:
        return (*_reviewed_response(found, levels, notes, progress), None)
    why = "it was fitted beside thresholds that were not measured"
    noise = _raw_noise(recording, levels, why, notes)
    return levels.black_level, levels.saturation, None if noise is None else 1.0, noise


def _reviewed_response(
    found: _Consistency, levels: FrameLevels, notes: Assumptions, progress
) -> tuple[float, float, float | None]:
    """The frames' black and clip levels, and the power of v their free curve is if linear.

    A linear response needs a black level a DAVIS can have: one its search had to put below
    zero means the curve is not the line it looked like.
    """
    pile_up = levels.black_level if levels.black_level > 0 else None
    black, power, straightness = linear_fit(found.response, pile_up)
    is_linear = straightness < (RAW_LINEAR_RMS if _raw_marks(levels) else LINEAR_RMS)
    progress(
        f"response {'linear' if is_linear else 'not linear'}: the free curve is a power "
        f"{power:.2f} of v {'-' if black >= 0 else '+'} {abs(black):.3f} to {straightness:.3f} RMS"
    )
    if is_linear and pile_up is None and black < 0:
        above = _linear_above_dark_end(found, progress)
        black, power = (0.0, above) if above is not None else (black, power)
    if is_linear and pile_up is None and not BLACK_LEVEL.holds(black):
        notes.add(
            "response",
            f"the free curve is straight only in ln(v - {black:.3f}), below any black level a "
            "frame can have",
            "a response the fit learns, black at 0",
        )
        is_linear = False
    black = levels.black_level or (black if is_linear else 0.0)
    return black, levels.saturation, power if is_linear else None


def _raw_marks(levels: FrameLevels) -> bool:
    """True when the frames pile up at a black level above 0 and clip below full scale."""
    return levels.black_level > 0 and levels.saturation < 1.0


def _linear_above_dark_end(found: _Consistency, progress) -> float | None:
    """The power of v above the dark end of a curve straight only below zero, if it is a line.

    The line is that of frames with black at 0; None where the curve is not it.

    Noise in the darkest values flattens the free curve's dark end (their errors attenuate the
    slope they are regressed on), which the search for the straightest black reads as a level
    below zero: -0.03 to -0.06 on linear 8-bit frames with black at 0. Above the dark end such a
    curve is straight with black at 0, and its power is the thresholds it was solved beside over
    the true ones, which a DAVIS keeps within :data:`THRESHOLD_SCALE` of each other at the
    nominal scale; a tone curve that only looks straight is not.
    """
    if np.count_nonzero(found.response.knots >= DARK_END) < MIN_BRIGHT_KNOTS:
        return None
    _, power, straightness = linear_fit(found.response, 0.0, above=DARK_END)
    if straightness >= LINEAR_RMS or not THRESHOLD_SCALE.holds(power):
        return None
    progress(
        f"response linear, black at 0: above {DARK_END:g} of full scale the free curve is a "
        f"power {power:.2f} of v to {straightness:.3f} RMS (the noise of the darkest values "
        "bends it below)"
    )
    return power


def _raw_noise(
    recording: CalibrationInput, levels: FrameLevels, why: str, notes: Assumptions
) -> FrameNoise | None:
    """The noise of frames whose response could not be measured, where they are taken as raw.

    A DAVIS's APS values are raw ADC counts, linear in the light, unless software put a tone
    curve on them; such a curve shows in the frames' noise, which falls as the level rises
    (:attr:`FrameNoise.falls`). Frames whose noise does not fall are taken as raw and linear
    (their noise returned, for the fit to weigh them by); those whose noise falls, or that are
    too smooth to tell, get a response the fit learns (None). Either is stored as assumed, with
    ``why``.
    """
    noise = frame_noise(recording.frames, levels.black_level, levels.saturation, recording.adc_step)
    if noise.falls is False and BLACK_LEVEL.holds(levels.black_level):
        notes.add("response", why, _RAW_RESPONSE)
        return noise
    notes.add("response", why, "a response the fit learns")
    return None


_RAW_RESPONSE = (
    "linear above the black level, as a raw DAVIS frame's: the frames' noise does not fall as "
    "their level rises, as a tone curve's would (--response learned learns one)"
)


def _without_consistency(
    recording: CalibrationInput,
    levels: FrameLevels,
    dead_time: int,
    why: str,
    notes: Assumptions,
) -> SensorCalibration:
    """The nominal sensor with what the frames and events alone measure.

    They measure the levels, the dead time, whether the frames are raw and then their noise.
    ``why``: the reason the frames and events could not measure the rest.
    """
    theta, spread = _nominal()
    notes.add("thresholds", why, _NOMINAL)
    notes.add("latency_us", why, "no latency (0 ms)")
    notes.add("pixel_factors", why, "every pixel's factor 1")
    noise = _raw_noise(recording, levels, why, notes)
    return SensorCalibration(
        threshold_on=float(theta[0]),
        threshold_off=float(theta[1]),
        threshold_on_sd=float(spread[0]),
        threshold_off_sd=float(spread[1]),
        black_level=levels.black_level,
        saturation=levels.saturation,
        response_linear=noise is not None,
        dead_time_us=dead_time,
        noise_gain=noise.gain if noise else 0.0,
        noise_floor=noise.floor if noise else 0.0,
        source="assumed",
        method="the frames' levels, noise trend and the pixels' dead time measured; nothing "
        "else could be",
        assumed=dict(notes.reasons),
    )
