import numpy as np
import pytest

from davis_io.colorfilter import filter_weights
from davis_io.emulator.aps import (
    ApsSettings,
    expose,
    integrate_exposure,
    quantise,
    sensor_noise,
    subframe_times,
    trapezoid_weights,
)
from davis_io.emulator.colorfilter import sensor_channels
from davis_io.emulator.response import apply_response, film, reinhard_gamma, response_table
from davis_io.errors import UsageError
from davis_io.types import ColorFilter


def test_trapezoid_weights_of_17_subframes():
    # Ends half weight, 16 intervals: 1/32, then fifteen 1/16, then 1/32.
    weights = trapezoid_weights(17)
    np.testing.assert_allclose(weights, [1 / 32] + [1 / 16] * 15 + [1 / 32])
    with pytest.raises(UsageError):
        trapezoid_weights(1)


def test_subframe_times_cover_the_exposure_inclusive():
    # 150 ms over 16 intervals = 9375 µs apart.
    times = subframe_times(1000, 151_000, 17)
    assert times[0] == 1000 and times[-1] == 151_000
    assert set(np.diff(times)) == {9375}


def test_blurred_frame_is_the_weighted_sum_before_the_response():
    rng = np.random.default_rng(1)
    subframes = rng.uniform(0.001, 5.0, size=(17, 6, 8))
    weights = trapezoid_weights(17)
    expected = sum(w * s for w, s in zip(weights, subframes, strict=True))
    np.testing.assert_allclose(integrate_exposure(subframes, weights), expected, rtol=1e-12)
    # Noise-free frame = quantised response of gain * exposure * weighted sum.
    settings = ApsSettings(gain_per_s=1 / 0.15)
    frame = expose(subframes, 0.15, settings, rng=None)
    assert frame.dtype == np.uint16
    np.testing.assert_array_equal(frame, np.round(reinhard_gamma(expected) * 1023))


def test_response_curves_hand_values():
    # (1 / 2) ** (1 / 2.2) = 0.729740; film is 0.5 at its midpoint 0.35.
    assert reinhard_gamma(np.array(1.0)) == pytest.approx(0.729740, abs=1e-6)
    assert film(np.array(0.35)) == pytest.approx(0.5)
    assert reinhard_gamma(np.array(0.0)) == 0.0
    assert np.all(np.diff(film(np.geomspace(1e-4, 1e4, 50))) > 0)
    with pytest.raises(UsageError, match="unknown response"):
        apply_response("gamma-2.4", np.ones(2))


def test_response_table_is_against_log_radiance_times_seconds():
    # gain 1/0.15: radiance 1 for 0.15 s (ln 0.15) reads reinhard_gamma(1).
    log_exposure, value = response_table("reinhard_gamma", 1 / 0.15, samples=2001)
    assert np.interp(np.log(0.15), log_exposure, value) == pytest.approx(0.729740, abs=1e-4)
    assert np.all(np.diff(value) >= 0)


def test_quantise_to_ten_bits():
    values = np.array([-0.5, 0.0, 0.5, 1.0, 2.0])
    assert quantise(values, 10).tolist() == [0, 0, 512, 1023, 1023]  # round(511.5) = 512


def test_shot_noise_has_poisson_spread():
    # 1000 electrons per unit at x = 1: std = sqrt(1000) / 1000 = 0.0316 (read noise 0).
    rng = np.random.default_rng(2)
    noisy = sensor_noise(np.ones(100_000), 1000.0, 0.0, rng)
    assert noisy.mean() == pytest.approx(1.0, abs=1e-3)
    assert noisy.std() == pytest.approx(np.sqrt(1000) / 1000, rel=0.02)


def test_rggb_weights_and_monochrome_luminance():
    weights = filter_weights(ColorFilter.RGGB, 2, 2)
    np.testing.assert_array_equal(weights[0, 0], [1, 0, 0])
    np.testing.assert_array_equal(weights[0, 1], [0, 1, 0])
    np.testing.assert_array_equal(weights[1, 0], [0, 1, 0])
    np.testing.assert_array_equal(weights[1, 1], [0, 0, 1])
    mono = filter_weights(ColorFilter.MONO, 2, 2)
    np.testing.assert_allclose(mono[1, 1], [0.2126, 0.7152, 0.0722])
    rgb = np.ones((2, 2, 3), np.float32)
    assert sensor_channels(rgb, ColorFilter.MONO).shape == (2, 2, 1)
    assert sensor_channels(rgb, ColorFilter.RGGB).shape == (2, 2, 3)
