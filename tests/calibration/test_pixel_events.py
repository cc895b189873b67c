"""The path a pixel's light is read along, and the blur term over its pieces, by hand."""

from __future__ import annotations

import numpy as np
import pytest

from davis_io.calibration.pixel_events import _mean_exp, event_path, log_blur, pixel_events


def _path():
    # pixel 0: ON at 100, ON at 200, OFF at 300 µs; pixel 1: no event; pixel 2: OFF at 150 µs
    return event_path(
        np.array([100, 150, 200, 300]), np.array([0, 2, 0, 0]), np.array([1, 0, 1, 0], bool), 3
    )


def _levels(path, time_us):
    on, off, _ = path.read(time_us)
    before_on, before_off, _ = path.read(0)
    return on - before_on, off - before_off


@pytest.mark.parametrize(
    ("time_us", "on", "off"),
    [
        (99, 0.0, 0.0),  # flat before the first event, up to a microsecond before it
        (100, 1.0, 0.0),
        (150, 1.5, 0.0),  # straight between two ON events
        (250, 2.5, 0.0),  # half an ON level past the last one, midway to the opposite event
        (275, 2.25, 0.5),  # then straight down to the OFF level
        (300, 2.0, 1.0),
        (10_000, 2.0, 1.0),  # flat after the last event
    ],
)
def test_the_light_is_read_straight_between_levels_and_past_a_turn(time_us, on, off):
    levels = _levels(_path(), time_us)
    assert levels[0][0] == pytest.approx(on) and levels[1][0] == pytest.approx(off)
    assert levels[0][1] == levels[1][1] == 0.0  # a pixel without events stays put
    assert levels[1][2] == (1.0 if time_us >= 150 else 0.0)


def test_the_levels_between_exposure_starts_are_read_off_the_path():
    events = pixel_events(_path(), np.array([0, 150, 275]), np.array([100, 250, 400]))
    np.testing.assert_allclose(events.between_on, [[1.5, 0, 0], [0.75, 0, 0]])
    np.testing.assert_allclose(events.between_off, [[0, 0, 1], [0.5, 0, 0]])


def test_the_blur_term_integrates_the_exponential_of_the_path():
    theta_on, theta_off = 0.3, 0.2
    events = pixel_events(_path(), np.array([0]), np.array([400]))
    ramp = (np.exp(theta_on) - 1) / theta_on  # the mean of e^(x t) over a one-level climb
    # pixel 0, per microsecond: flat 99, one climb over 1 and over 100, then half a level up
    # over 50, back down over 50 (0.5 ON up, 1 OFF down), flat 100 at 2 ON - 1 OFF
    top = 2.5 * theta_on
    bottom = 2 * theta_on - theta_off
    blur = (
        99
        + ramp
        + 100 * np.exp(theta_on) * ramp
        + 50 * np.exp(2 * theta_on) * (np.exp(0.5 * theta_on) - 1) / (0.5 * theta_on)
        + 50 * (np.exp(bottom) - np.exp(top)) / (bottom - top)
        + 100 * np.exp(bottom)
    ) / 400
    # pixel 2: flat 149, one OFF step over 1, flat 250 one OFF level down
    down = (1 - np.exp(-theta_off)) / theta_off
    expected = [np.log(blur), 0.0, np.log((149 + down + 250 * np.exp(-theta_off)) / 400)]
    alone = log_blur(events, theta_on, theta_off).value  # single precision
    np.testing.assert_allclose(alone[0], expected, rtol=1e-6)
    with_slopes = log_blur(events, theta_on, theta_off, derivatives=True).value
    np.testing.assert_array_equal(with_slopes, alone)


def test_the_blur_terms_derivatives_match_finite_differences():
    events = pixel_events(_path(), np.array([0, 150]), np.array([140, 400]))
    # A step large enough that single precision's rounding (1e-7) is 1e-4 of the difference.
    on, off, step = np.array([0.3, 0.25, 0.4]), np.array([0.2, 0.15, 0.35]), 1e-3
    blur = log_blur(events, on, off, derivatives=True)

    def value(on, off):
        return log_blur(events, on, off).value.astype(np.float64)

    by_on = value(on + step, off) - value(on - step, off)
    by_off = value(on, off + step) - value(on, off - step)
    np.testing.assert_allclose(blur.d_on, by_on / (2 * step), atol=2e-4)
    np.testing.assert_allclose(blur.d_off, by_off / (2 * step), atol=2e-4)
    assert np.abs(blur.d_on).max() > 0.1 and np.abs(blur.d_off).max() > 0.05


def test_latency_reads_the_path_that_much_later():
    late = pixel_events(_path(), np.array([0, 150]), np.array([140, 300]), latency_us=60)
    moved = pixel_events(_path(), np.array([60, 210]), np.array([200, 360]))
    np.testing.assert_allclose(log_blur(late, 0.3, 0.2).value, log_blur(moved, 0.3, 0.2).value)
    np.testing.assert_allclose(late.between_on, moved.between_on)


def test_the_blur_slope_holds_in_single_precision_where_its_terms_cancel():
    climb = np.array([1e-7, -3e-5, 1e-3, -9.9e-3, 0.0999, 0.1, -0.1001, -0.5, 3.0], np.float32)
    exact = climb.astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        closed = (np.expm1(exact) * (exact - 1) + exact) / exact**2
    series = 0.5 + exact / 3 + exact**2 / 8 + exact**3 / 30
    expected = np.where(np.abs(exact) < 1e-3, series, closed)
    mean, slope = _mean_exp(climb.copy(), derivative=True)
    assert slope.dtype == np.float32
    np.testing.assert_allclose(slope, expected, rtol=2e-6)
    np.testing.assert_allclose(mean, np.expm1(exact) / exact, rtol=1e-6)
