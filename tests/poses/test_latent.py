import cv2
import numpy as np
import pytest

from davis_io.errors import UsageError
from davis_io.poses.latent import ResponseCurve, auto_white, latent_images, sharpness
from davis_io.types import ColorFilter, Frame


def frame_of(image, bit_depth=10):
    return Frame(image, 0, 100, 0, 120, bit_depth=bit_depth)


def test_mono_latent_frames_without_events_are_the_frame_in_8_bit():
    image = np.array([[0, 1023], [511, 100]], np.uint16)
    images = latent_images(
        frame_of(image), np.zeros((2, 2, 2)), [0.25, 0.5, 0.25], 0.3, ColorFilter.MONO
    )
    # 8-bit value = round(code / 1023 * 255): 0, 255, 127 (127.38), 25 (24.93).
    assert len(images) == 3
    assert all(np.array_equal(im, [[0, 255], [127, 25]]) for im in images)


def test_bayer_mosaic_is_demosaiced_after_the_edi():
    mosaic = np.zeros((4, 4), np.uint8)
    mosaic[0::2, 0::2] = 200  # every red site lit: an RGGB mosaic of a pure red scene
    counts = np.zeros((1, 4, 4))
    counts[0, 0::2, 0::2] = np.log(2) / 0.3  # red sites double their brightness in the bin
    first, last = latent_images(frame_of(mosaic, 8), counts, [0.5, 0.5], 0.3, ColorFilter.RGGB)
    assert first.shape == (4, 4, 3)
    # L_0 = 200 / (0.5 + 0.5 * 2) = 133.3, L_1 = 266.7 -> clipped to 255 when written.
    assert first[1, 1, 0] == 133 and last[1, 1, 0] == 255
    assert first[1, 1, 2] == 0  # no blue anywhere
    with pytest.raises(UsageError, match="demosaiced"):
        latent_images(frame_of(mosaic, 8), counts, [0.5, 0.5], 0.3, ColorFilter.RGWB)


def test_response_curve_runs_the_edi_on_linear_values():
    exposure = np.linspace(0, 4, 401)
    curve = ResponseCurve(exposure, np.sqrt(exposure / 4))  # value = sqrt(x / 4)
    assert curve.to_linear(np.array([0.5]))[0] == pytest.approx(1.0, abs=1e-3)
    # Blurry values 0.5 and 1 -> linear 1 and 4; the first pixel's one bin doubles it:
    # L_0 = 1 / 1.5, L_1 = 4/3 (linear). White is the blurry exposures' 99.5th percentile,
    # 1 + 0.995 * 3 = 3.985 (below median / 0.18 = 13.9), and the display gamma 2.2 gives
    # (2/3 / 3.985) ** (1/2.2) = 0.444 and (4/3 / 3.985) ** (1/2.2) = 0.608: 113 and 155 in
    # 8 bits, whatever the curve.
    image = np.array([[0.5, 1.0]]) * 255
    counts = np.array([[[np.log(2) / 0.3, 0.0]]])
    first, last = latent_images(
        frame_of(image.round().astype(np.uint8), 8),
        counts,
        [0.5, 0.5],
        0.3,
        ColorFilter.MONO,
        curve,
    )
    assert abs(int(first[0, 0]) - 113) <= 1 and abs(int(last[0, 0]) - 155) <= 1
    assert int(first[0, 1]) == int(last[0, 1]) == 255  # no events: the brightest stays white


def test_a_few_glaring_pixels_do_not_darken_the_rest():
    # 990 pixels at 0.1 and 10 lamps at 100: white would be 100 by the 99.5th percentile,
    # showing the room at (0.001) ** (1/2.2) = 4 % grey; the median at mid-grey puts white at
    # 0.1 / 0.18 = 0.556 and the room at 0.18 ** (1/2.2) = 46 %.
    exposure = np.concatenate([np.full(990, 0.1), np.full(10, 100.0)])
    assert auto_white(exposure) == pytest.approx(0.1 / 0.18)
    # Without highlights the bright percentile bounds it: nothing clips that need not.
    assert auto_white(np.linspace(1.0, 2.0, 1001)) == pytest.approx(1.995)


def test_sharpness_prefers_the_sharp_image():
    rng = np.random.default_rng(0)
    sharp = (rng.random((64, 64)) * 255).astype(np.uint8)
    assert sharpness(sharp) > sharpness(cv2.GaussianBlur(sharp, (7, 7), 2)) > 0
    assert sharpness(np.full((8, 8), 9, np.uint8)) == 0
