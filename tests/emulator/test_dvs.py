import dataclasses

import numpy as np
import pytest

from davis_io.colorfilter import filter_weights
from davis_io.emulator.colorfilter import through_filter
from davis_io.emulator.dvs import DVS_PRESETS, DvsParams, DvsPixels, intensity_factor, lin_log
from davis_io.emulator.sensor import default_sensor
from davis_io.errors import UsageError
from davis_io.types import ColorFilter

EXACT = DvsParams(threshold_on=0.2, threshold_off=0.2, threshold_sigma=0.0)


def radiance_for_log(log_intensity):
    """Radiance whose lin-log value (of I = 255 * radiance) is ``log_intensity``."""
    return np.exp(np.asarray(log_intensity, np.float64)) / 255


def test_lin_log_is_linear_below_threshold_and_log_above():
    # T = 20: I = 10 gives 10 * ln(20) / 20 = 1.4978661; I = 40 gives ln 40 = 3.6888795.
    values = lin_log(np.array([0.0, 10.0, 20.0, 40.0]), 20.0)
    np.testing.assert_allclose(values, [0.0, 1.4978661, np.log(20), np.log(40)], rtol=1e-6)


def test_intensity_factor_curves():
    # fork: x = 255 / 255 = 1 -> (1/2) ** (1/2.2) = 0.72974; upstream: (235 + 20) / 275 = 0.92727.
    assert intensity_factor(np.array([255.0]), "reinhard_gamma")[0] == pytest.approx(
        0.72974, abs=1e-5
    )
    assert intensity_factor(np.array([235.0]), "affine")[0] == pytest.approx(0.92727, abs=1e-5)
    with pytest.raises(UsageError):
        intensity_factor(np.array([1.0]), "cubic")


def test_first_step_only_initialises():
    pixels = DvsPixels(EXACT, 2, 3, seed=0)
    events = pixels.step(np.ones((2, 3)), 0)
    assert len(events) == 0


def test_rise_of_k_thresholds_gives_k_on_events_spread_over_the_step():
    # Pixel (0, 0) rises by 3.5 thresholds, pixel (0, 1) by 1.5, between t = 1000 and 2000 µs.
    # M = 3 (largest count), so events fire at 1000 + (i + 1) * 1000 // 3 = 1333, 1666, 2000;
    # the one-event pixel fires at the first sub-step, 1333.
    pixels = DvsPixels(EXACT, 1, 3, seed=0)
    pixels.step(radiance_for_log([[1.0, 1.0, 1.0]]), 1000)
    events = pixels.step(radiance_for_log([[1.0 + 3.5 * 0.2, 1.0 + 1.5 * 0.2, 1.0]]), 2000)
    assert events["t"].tolist() == [1333, 1333, 1666, 2000]
    assert events["x"].tolist() == [0, 1, 0, 0]
    assert events["y"].tolist() == [0, 0, 0, 0]
    assert events["p"].tolist() == [1, 1, 1, 1]
    # The remainders (0.5 threshold) stay: holding still fires nothing; falling to 0.9 thresholds
    # below the start gives floor((3.0 + 0.9) / ... ) : d = (1 - 0.18) - (1 + 0.6) = -0.78 -> 3 OFF.
    assert len(pixels.step(radiance_for_log([[1.7, 1.3, 1.0]]), 3000)) == 0
    falling = pixels.step(radiance_for_log([[1.0 - 0.18, 1.3, 1.0]]), 4000)
    assert falling["t"].tolist() == [3333, 3666, 4000]
    assert falling["p"].tolist() == [-1, -1, -1]


def test_low_pass_delays_a_step_as_its_recursion_says():
    # Cutoff 100 Hz, steps of 100 µs: tau = 1 / (2 pi 100) s, eps = f * 0.1 ms / tau = f * 0.0628
    # with f = intensity factor of the new intensity. After a log step of 0.9 the filtered
    # difference after n steps is 0.9 * (1 - (1 - eps) ** n); the first event fires at the first
    # n where that reaches the 0.2 threshold; with the one-step delay, one step later. (0.9 keeps
    # the last threshold crossing away from rounding: floor(0.9 / 0.2) = 4 events.)
    target = 1.9
    factor = float(
        intensity_factor(255 * radiance_for_log(np.array([target])), "reinhard_gamma")[0]
    )
    epsilon = factor * 100e-6 * 2 * np.pi * 100
    first_step = int(np.ceil(np.log(1 - 0.2 / 0.9) / np.log(1 - epsilon)))
    for delay, expected_step in ((False, first_step), (True, first_step + 1)):
        params = DvsParams(threshold_sigma=0.0, cutoff_hz=100.0, one_step_delay=delay)
        pixels = DvsPixels(params, 1, 1, seed=0)
        pixels.step(radiance_for_log([[1.0]]), 0)
        times = []
        for step in range(1, 1000):
            times += pixels.step(radiance_for_log([[target]]), step * 100)["t"].tolist()
        assert times[0] == expected_step * 100
        # The filter converges ((1 - eps) ** 1000 < 1e-5): 4 events in total.
        assert len(times) == 4


def test_refractory_period_drops_events_and_keeps_their_change():
    # 3.5 thresholds in one 1000 µs step: candidates at 1333, 1666, 2000 µs. With 500 µs dead
    # time 1666 - 1333 <= 500 is dropped, 2000 - 1333 > 500 fires. The dropped threshold stays in
    # the difference and fires at the next step (3000 µs).
    params = DvsParams(threshold_sigma=0.0, refractory_us=500)
    pixels = DvsPixels(params, 1, 1, seed=0)
    pixels.step(radiance_for_log([[1.0]]), 1000)
    assert pixels.step(radiance_for_log([[1.7]]), 2000)["t"].tolist() == [1333, 2000]
    assert pixels.step(radiance_for_log([[1.7]]), 3000)["t"].tolist() == [3000]


def test_leak_fires_on_events_at_the_leak_rate():
    # Leak 10 Hz with no jitter: the base falls by 10 * dt * theta per second, so a still pixel
    # fires one ON event every 100 ms.
    params = DvsParams(threshold_sigma=0.0, leak_rate_hz=10.0)
    pixels = DvsPixels(params, 1, 4, seed=0)
    still = radiance_for_log(np.full((1, 4), 1.0))
    events = [pixels.step(still, t) for t in range(0, 350_001, 1000)]
    events = np.concatenate(events)
    assert np.all(events["p"] == 1)
    for x in range(4):
        times = events["t"][events["x"] == x]
        np.testing.assert_allclose(times, [100_000, 200_000, 300_000], atol=1000)


def test_threshold_mismatch_has_the_configured_spread():
    # 90 k pixels: the sample standard deviation is within ~0.5 % of sigma (stderr 0.24 %).
    pixels = DvsPixels(DVS_PRESETS["noisy"], 260, 346, seed=3)
    for thresholds in (pixels.threshold_on, pixels.threshold_off):
        assert thresholds.mean() == pytest.approx(0.3, abs=5e-4)
        assert thresholds.std() == pytest.approx(0.03, rel=0.01)
    assert np.log10(pixels.leak_scale).std() == pytest.approx(0.01, rel=0.02)
    other = DvsPixels(DVS_PRESETS["noisy"], 260, 346, seed=4)
    assert not np.array_equal(pixels.threshold_on, other.threshold_on)


def test_shot_noise_rate_matches_the_parameter_in_the_dark():
    # Zero intensity: p = rate / 2 * dt per polarity, so both polarities together fire at
    # `rate` Hz per pixel: 10 000 pixels * 0.1 s * 100 Hz = 100 000 events (stderr ~ 0.3 %).
    params = DvsParams(threshold_sigma=0.0, shot_noise_rate_hz=100.0)
    pixels = DvsPixels(params, 100, 100, seed=5)
    dark = np.zeros((100, 100))
    events = np.concatenate([pixels.step(dark, t) for t in range(0, 100_001, 1000)])
    assert len(events) == pytest.approx(100_000, rel=0.03)
    assert (events["p"] == 1).mean() == pytest.approx(0.5, abs=0.01)


def test_colour_events_follow_each_pixels_own_channel():
    # Only red brightens: on an RGGB sensor only (even row, even column) pixels fire.
    weights = filter_weights(ColorFilter.RGGB, 4, 6)
    grey = np.full((4, 6, 3), 0.5)
    red = grey.copy()
    red[..., 0] *= 3.0
    pixels = DvsPixels(EXACT, 4, 6, seed=0)
    pixels.step(through_filter(grey, weights), 0)
    events = pixels.step(through_filter(red, weights), 1000)
    assert len(events) == 6 * 5  # 6 red sites, floor(ln 3 / 0.2) = 5 events each
    assert np.all(events["x"] % 2 == 0) and np.all(events["y"] % 2 == 0)


def test_bad_input_is_rejected():
    pixels = DvsPixels(EXACT, 2, 2, seed=0)
    with pytest.raises(UsageError, match="shape"):
        pixels.step(np.ones((3, 2)), 0)
    pixels.step(np.ones((2, 2)), 10)
    with pytest.raises(UsageError, match="not after"):
        pixels.step(np.ones((2, 2)), 10)


def test_same_seed_same_events():
    rng = np.random.default_rng(0)
    frames = rng.uniform(0.01, 10, size=(20, 16, 16))
    streams = []
    for _ in range(2):
        pixels = DvsPixels(DVS_PRESETS["noisy"], 16, 16, seed=9)
        streams.append(np.concatenate([pixels.step(f, 1000 * i) for i, f in enumerate(frames)]))
    assert len(streams[0]) > 100
    assert np.array_equal(streams[0], streams[1])  # field by field: padding bytes are undefined


def test_refractory_period_shorter_than_a_sub_step_is_inactive():
    # 4.5 thresholds in a 2000 µs step: M = 4 sub-steps of 500 µs. A 500 µs dead time is not
    # longer than the sub-step, so (as in v2e) it is not applied: 4 events, 500 µs apart.
    params = DvsParams(threshold_sigma=0.0, refractory_us=500)
    pixels = DvsPixels(params, 1, 1, seed=0)
    pixels.step(radiance_for_log([[1.0]]), 0)
    assert pixels.step(radiance_for_log([[1.9]]), 2000)["t"].tolist() == [500, 1000, 1500, 2000]


@pytest.mark.parametrize(("refractory_us", "dead_time_us"), [(0, 0), (975, 2000), (2500, 2500)])
def test_the_truth_states_the_dead_time_a_backlogged_pixel_fires_at(refractory_us, dead_time_us):
    # At 2 ms DVS steps a pixel held back by a 975 µs refractory period fires again only in a
    # later step (see the refractory test above: candidates share the step's sub-steps).
    sensor = default_sensor("clean", "reinhard_gamma", ColorFilter.MONO)
    sensor = dataclasses.replace(
        sensor, dvs=dataclasses.replace(sensor.dvs, refractory_us=refractory_us)
    )
    assert sensor.to_json(step_us=2000)["dead_time_us"] == dead_time_us
