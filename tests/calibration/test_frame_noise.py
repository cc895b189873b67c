"""Linear frames' shot and read noise are measured from the frames, mono or a colour mosaic."""

import numpy as np
import pytest

from davis_io.calibration.frame_noise import FALL_RATIO, frame_noise
from davis_io.calibration.response_fit import frame_levels
from davis_io.emulator.aps import ApsSettings, expose, linear_noise
from davis_io.emulator.response import Response

RESPONSE = Response("linear", black=0.04, slope=0.4, saturation=0.95)
SETTINGS = ApsSettings(RESPONSE, gain_per_s=1 / 0.15)
STEP = 1 / 1023


def _frames(rng, colour_factors=None, count=6, settings=SETTINGS):
    """Frames of a smooth scene from near black to past the clip level, each a little apart."""
    rows, columns = np.mgrid[0:120, 0:160]
    factors = np.ones(rows.shape) if colour_factors is None else colour_factors(rows, columns)
    images = []
    for k in range(count):
        radiance = np.exp(-7 + 8.5 * columns / 160) * (1 + 0.2 * np.sin(rows / 15 + k))
        images.append(expose((radiance * factors)[None], 0.15, settings, rng, np.ones(1)))
    return np.stack(images) * STEP


def test_the_emulators_frame_noise_is_its_electrons_over_the_slope():
    # Slope 0.4 per unit x, 3000 electrons per unit x, 4 electrons read noise, 10 bits:
    # gain 0.4 / 3000 = 1.3333e-4; floor (0.4 * 4 / 3000)^2 + (1/1023)^2 / 12
    # = 2.8444e-7 + 7.963e-8 = 3.6407e-7.
    noise = linear_noise(RESPONSE, SETTINGS)
    assert noise["gain"] == pytest.approx(1.33333e-4, rel=1e-4)
    assert noise["floor"] == pytest.approx(3.6407e-7, rel=1e-4)
    assert linear_noise(Response("film"), SETTINGS) == {}


def test_shot_and_read_noise_are_measured_from_mono_frames():
    truth = linear_noise(RESPONSE, SETTINGS)
    measured = frame_noise(_frames(np.random.default_rng(0)), 0.04, 0.95, STEP)
    # Measured: gain 2 % low, floor 6 % low (offset 2.68 ADC steps against 2.79).
    assert measured.gain == pytest.approx(truth["gain"], rel=0.15)
    assert measured.floor == pytest.approx(truth["floor"], rel=0.3)


def test_a_colour_mosaic_is_read_by_same_colour_neighbours():
    # Red, green and blue read 1, 0.6 and 0.3 of the light: next-door pixels differ by far
    # more than the noise (40 % of the value), same-colour pixels two apart do not.
    def mosaic(rows, columns):
        return np.where(
            (rows % 2 == 0) & (columns % 2 == 0),
            1.0,
            np.where((rows % 2 == 1) & (columns % 2 == 1), 0.3, 0.6),
        )

    truth = linear_noise(RESPONSE, SETTINGS)
    measured = frame_noise(_frames(np.random.default_rng(1), mosaic), 0.04, 0.95, STEP)
    # Measured: gain 10 % high, floor 22 % low.
    assert measured.gain == pytest.approx(truth["gain"], rel=0.2)
    assert measured.floor == pytest.approx(truth["floor"], rel=0.35)


def test_noise_free_frames_show_only_the_rounding():
    clean = _frames(None)
    measured = frame_noise(clean, 0.04, 0.95, STEP)
    assert measured.floor == pytest.approx(STEP**2 / 12)
    # Shot noise as large as read noise only far above black (110 ADC steps measured, 2.8
    # with the noise): the frame loss stays nearly the plain one.
    assert measured.offset > 30 * STEP


@pytest.mark.parametrize(
    ("response", "falls"),
    [
        (RESPONSE, False),  # raw: the shot noise grows with the level
        (Response("reinhard_gamma"), True),  # a gamma squeezes the bright values' noise
        (Response("film"), True),
        (Response("s_curve"), True),
    ],
)
def test_a_tone_curves_noise_falls_as_the_level_rises_and_a_raw_frames_never(response, falls):
    settings = ApsSettings(response, gain_per_s=1 / 0.15)
    frames = _frames(np.random.default_rng(2), settings=settings)
    levels = frame_levels(frames, STEP)  # the clipped values, which have no noise, left out
    assert frame_noise(frames, levels.black_level, levels.saturation, STEP).falls is falls


def test_a_frame_too_flat_for_three_bands_tells_nothing():
    assert FALL_RATIO == 0.5
    flat = np.full((2, 40, 40), 0.5) + np.random.default_rng(3).normal(0, 0.01, (2, 40, 40))
    assert frame_noise(flat, 0.0, 1.0, STEP).falls is None
