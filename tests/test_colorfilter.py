import cv2
import numpy as np
import pytest

from davis_io.colorfilter import (
    DEVICE_COLOR_FILTERS,
    LUMINANCE_WEIGHTS,
    bayer_to_rgb_code,
    filter_channels,
    filter_weights,
)
from davis_io.errors import UsageError
from davis_io.types import ColorFilter


def test_rggb_code_demosaics_a_hand_made_mosaic_into_rgb():
    # One RGGB tile of a flat scene with R = 200, G = 100, B = 50: red at (even, even), blue at
    # (odd, odd). Tiled 3x3 so that OpenCV's border handling does not reach the centre pixels.
    tile = np.array([[200, 100], [100, 50]], np.uint8)
    rgb = cv2.cvtColor(np.tile(tile, (3, 3)), bayer_to_rgb_code(ColorFilter.RGGB))
    assert rgb[2:4, 2:4].reshape(-1, 3).tolist() == [[200, 100, 50]] * 4
    # OpenCV names patterns from the second row: our RGGB is its BayerBG, not its BayerRG.
    assert bayer_to_rgb_code(ColorFilter.RGGB) == cv2.COLOR_BayerBG2RGB
    assert bayer_to_rgb_code(ColorFilter.RGGB) != cv2.COLOR_BayerRG2RGB


def test_bggr_code_swaps_the_red_and_blue_sites():
    tile = np.array([[50, 100], [100, 200]], np.uint8)  # blue at (even, even), red at (odd, odd)
    rgb = cv2.cvtColor(np.tile(tile, (3, 3)), bayer_to_rgb_code(ColorFilter.BGGR))
    assert rgb[2, 2].tolist() == [200, 100, 50]


@pytest.mark.parametrize("color_filter", [ColorFilter.MONO, ColorFilter.RGWB, ColorFilter.BWGR])
def test_non_bayer_patterns_have_no_demosaic_code(color_filter):
    with pytest.raises(UsageError, match=color_filter.value):
        bayer_to_rgb_code(color_filter)


def test_channel_index_per_pixel_reads_the_tile_row_by_row():
    # RGGB: row 0 is R G R, row 1 is G B G; channel indices R=0, G=1, B=2.
    assert filter_channels(ColorFilter.RGGB, 2, 3).tolist() == [[0, 1, 0], [1, 2, 1]]
    assert filter_channels(ColorFilter.MONO, 1, 2).tolist() == [[3, 3]]
    assert filter_channels(ColorFilter.RGWB, 2, 2) is None
    assert filter_channels(ColorFilter.RGGB, 0, 0).shape == (0, 0)


def test_weights_pick_one_channel_or_luminance():
    weights = filter_weights(ColorFilter.RGGB, 2, 2)
    assert weights[1, 1].tolist() == [0, 0, 1]  # (odd, odd) is blue
    assert np.allclose(filter_weights(ColorFilter.MONO, 1, 1)[0, 0], [0.2126, 0.7152, 0.0722])
    assert LUMINANCE_WEIGHTS.sum() == pytest.approx(1.0)
    assert np.allclose(filter_weights(ColorFilter.RGWB, 2, 2)[1, 0], [1 / 3] * 3)


@pytest.mark.parametrize(
    ("register", "tile"),
    # libcaer's lookup: site (x, y) -> its table at ((x & 1) << 1) | (y & 1); the tiles of
    # values 1-4 (RGBG, GRGB, GBGR, BGRG) read R G / G B, G R / B G, G B / R G, B G / G R.
    [(1, [[0, 1], [1, 2]]), (2, [[1, 0], [2, 1]]), (3, [[1, 2], [0, 1]]), (4, [[2, 1], [1, 0]])],
)
def test_the_device_register_gives_libcaers_tile(register, tile):
    pattern = DEVICE_COLOR_FILTERS[register]
    assert filter_channels(pattern, 2, 2).tolist() == tile
    bayer_to_rgb_code(pattern)  # every Bayer register value can be demosaiced
