"""What the calibration does to save time gives what the long way gives."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from synthetic_recording import KnownSensor, synthetic_recording

from davis_io.calibration import dead_time as dead_time_module
from davis_io.calibration import estimate
from davis_io.calibration.consistency import KNOTS, THRESHOLD_RANGE, fit_pixel_factors
from davis_io.calibration.response_fit import frame_levels, place_knots
from davis_io.cores import cores_limited
from davis_io.emulator import Response


@pytest.fixture(scope="module")
def recording():
    found, _, _ = synthetic_recording(
        KnownSensor(0.25, 0.35, 0.04, Response("reinhard_gamma", gain=1.3, gamma=2.4))
    )
    return found


def _problems(recording, pixels):
    levels = frame_levels(recording.frames, recording.adc_step)
    knots = place_knots(recording.frames, levels, KNOTS, recording.adc_step)
    pairs = recording.pairs(0)
    return estimate._Problems(recording, pixels, levels, knots, pairs)


@pytest.mark.parametrize("cores", [1, 2])
def test_every_pixels_factors_fitted_block_by_block_equal_one_fit_of_all(
    recording, monkeypatch, cores
):
    # 64 x 48 = 3,072 pixels in blocks of 1,000: three whole blocks and one of 72.
    monkeypatch.setattr(estimate, "BLOCK_PIXELS", 1000)
    workers = []

    class CountedPool(ThreadPoolExecutor):
        def __init__(self, max_workers):
            workers.append(max_workers)
            super().__init__(max_workers)

    monkeypatch.setattr(estimate, "ThreadPoolExecutor", CountedPool)
    height, width = recording.shape
    subset = _problems(recording, np.arange(0, height * width, 5))
    problem = subset.at(2000)
    theta = np.array([0.26, 0.33])
    with cores_limited(cores):
        on, off = estimate._sensor_factors(recording, subset, problem, theta)
    assert workers == [cores]  # a fit told to use one core keeps to it
    every = _problems(recording, np.arange(height * width)).at(2000)
    fit_pixel_factors(every, theta, problem.solve(*theta)[1])
    np.testing.assert_allclose(on, every.factor_on, rtol=1e-9)
    np.testing.assert_allclose(off, every.factor_off, rtol=1e-9)
    assert np.std(on) > 0.02 and np.std(off) > 0.02  # the pixels' own thresholds were learned


def test_a_half_of_the_pixels_is_the_problem_of_those_pixels_alone(recording):
    subset = _problems(recording, np.arange(0, 3072, 3))
    for parity in (0, 1):
        half = subset.half(parity).at(1000).events
        alone = _problems(recording, subset.pixels[parity::2]).at(1000).events
        for name in ("between_on", "between_off", "flat_share", "piece_key", "piece_share"):
            np.testing.assert_array_equal(getattr(half, name), getattr(alone, name))
        assert half.pixels == len(subset.pixels[parity::2])


def test_the_pixels_are_drawn_until_they_hold_the_pairs_asked_for(recording, monkeypatch):
    monkeypatch.setattr(estimate, "SUBSET_PAIRS", 100)
    levels = frame_levels(recording.frames, recording.adc_step)
    pairs = recording.pairs(0)
    pixels = estimate._choose_pixels(recording, levels, pairs, seed=0)
    values = recording.frames.reshape(len(recording.frames), -1)
    inside = (values > levels.low) & (values < levels.high)
    usable = (inside[:-1] & inside[1:]).sum(axis=0)
    assert usable[pixels].min() >= 2
    # Enough pairs, and one pixel fewer would not be (every pixel here holds at most 7).
    assert usable[pixels].sum() >= 100 > usable[pixels].sum() - usable[pixels].min()
    assert 100 / 7 <= len(pixels) <= 50


def test_the_dead_time_of_every_nth_pixel_is_the_dead_time_of_all(monkeypatch):
    # 400 pixels, each rate-limited to one event per 1,500 µs while a bright edge passes
    # (40 events in a row), then quiet; read from 4,000 events, every 4th pixel.
    rng = np.random.default_rng(2)
    starts = rng.integers(0, 1_000_000, 400)
    times = (starts[:, None] + 1500 * np.arange(40)[None, :]).ravel()
    pixel = np.repeat(np.arange(400), 40)
    order = np.argsort(times, kind="stable")
    times, pixel = times[order], pixel[order]
    whole = dead_time_module.dead_time_us(times, pixel)
    monkeypatch.setattr(dead_time_module, "SAMPLE_EVENTS", 4_000)
    assert dead_time_module.dead_time_us(times, pixel) == whole == 1500


@pytest.mark.parametrize("linear_black", [None, 0.02])
def test_the_residuals_derivatives_by_the_thresholds_match_finite_differences(
    recording, linear_black
):
    # The free response is solved inside the residuals: their derivatives are the projected
    # derivatives of the events' change (exactly, the projection not depending on them).
    problem = _problems(recording, np.arange(0, 3072, 4)).at(1000)
    problem.factor_on = np.linspace(0.8, 1.2, len(problem.factor_on))
    problem.linear_black = linear_black
    # A step large enough that the blur term's single precision (1e-6 of ln M) rounds 5e-4 of it.
    theta, step = np.array([0.27, 0.31]), 1e-3
    residual, jacobian = problem.linearised(*theta)
    # The same residuals as solve's (which reads the blur term without its derivatives).
    np.testing.assert_allclose(residual, problem.solve(*theta)[0], atol=2e-6)
    for axis in range(2):
        shift = np.zeros(2)
        shift[axis] = step
        up, _ = problem.linearised(*(theta + shift))
        down, _ = problem.linearised(*(theta - shift))
        np.testing.assert_allclose(jacobian[:, axis], (up - down) / (2 * step), atol=5e-4)
    assert np.abs(jacobian).max() > 1.0


def test_the_threshold_fit_ends_where_the_disagreement_is_least(recording):
    problem = _problems(recording, np.arange(0, 3072, 2)).at(0)
    theta, best = estimate.fit_thresholds(problem, (0.3, 0.3))
    for shift in ([0.004, 0], [-0.004, 0], [0, 0.004], [0, -0.004]):
        assert problem.disagreement(*(theta + shift)) > best
    assert best == pytest.approx(problem.disagreement(*theta))


def test_the_threshold_fit_reaches_its_least_in_few_steps(monkeypatch):
    # A 20 ms exposure blurs a little: the disagreement is nearly flat along the common scale.
    # A damping of the steps that outweighed the curvature there left the fit creeping along
    # it, a fraction of the way per step: 20 to 25 steps to this tolerance.
    blurred, _, _ = synthetic_recording(
        KnownSensor(0.25, 0.35, 0.04, Response("reinhard_gamma", gain=1.3, gamma=2.4)),
        exposure_us=20_000,
    )
    problem = _problems(blurred, np.arange(0, 3072, 2)).at(0)
    linearised, steps = problem.linearised, []
    monkeypatch.setattr(
        problem, "linearised", lambda *theta: steps.append(theta) or linearised(*theta)
    )
    theta, _ = estimate.fit_thresholds(problem, (0.2, 0.2), tolerance=1e-4)
    assert len(steps) <= 10
    np.testing.assert_allclose(theta, [0.22, 0.32], atol=0.005)  # true medians 0.25, 0.35


def test_a_scale_the_frames_leave_free_stays_near_the_nominal():
    # Frames of a 4 ms exposure barely blur: the disagreement is flat along the common scale,
    # and the fit, started far above, ran to a bound of its range.
    sharp, _, _ = synthetic_recording(
        KnownSensor(0.25, 0.35, 0.02, Response("reinhard_gamma")), exposure_us=4_000
    )
    problem = _problems(sharp, np.arange(0, 3072, 2)).at(0)
    theta, _ = estimate.fit_thresholds(problem, (1.5, 1.9))
    low, high = THRESHOLD_RANGE
    assert 0.15 < np.sqrt(theta.prod()) < 0.6
    assert theta.min() > 2 * low and theta.max() < high / 2
