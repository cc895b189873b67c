import cv2
import numpy as np
from benchlib.plot import PALETTE, Series, axis_position, draw_speed_error, nice_ticks, write_png


def test_axis_position_linear_and_log():
    # Linear: 15 is halfway from 10 to 20, and the axis runs from pixel 500 up to 100 -> 300.
    assert axis_position(15.0, 10.0, 20.0, 500, 100) == 300
    # Log: 100 is halfway between 10 and 1000 in decades -> pixel 100 of 0..200.
    assert axis_position(100.0, 10.0, 1000.0, 0, 200, log=True) == 100
    assert axis_position(5.0, 5.0, 5.0, 0, 200) == 100  # a degenerate range sits in the middle


def test_nice_ticks():
    # (21.7 - 15.2) / 6 = 1.08 dB per tick, rounded up to a 1-2-5 step: 2 dB.
    assert nice_ticks(15.2, 21.7, log=False) == [16.0, 18.0, 20.0]
    assert nice_ticks(5.0, 200.0, log=True) == [5.0, 10.0, 20.0, 50.0, 100.0, 200.0]


def test_points_are_drawn_where_the_axes_put_them():
    series = [Series("fast / full", ((10.0, 20.0), (100.0, 25.0)))]
    image = draw_speed_error(series, "HDR PSNR (dB)", width=1000, height=600)
    assert image.shape == (600, 1000, 3) and image.dtype == np.uint8
    # Ranges: x 10 / 1.5 .. 100 * 1.5 (log), y floor(20 - 1) .. ceil(25 + 1) = 19 .. 26;
    # plot area x 80 .. 1000 - 260 - 40 = 700, y 600 - 60 = 540 (bottom) .. 40 (top).
    x = axis_position(100.0, 10 / 1.5, 150.0, 80, 700, log=True)
    y = axis_position(25.0, 19.0, 26.0, 540, 40)
    assert tuple(int(c) for c in image[y, x]) == PALETTE[0]


def test_no_series_gives_an_empty_plot(tmp_path):
    image = draw_speed_error([], "HDR PSNR (dB)")
    path = tmp_path / "plot" / "empty.png"
    write_png(path, image)
    read = cv2.imread(str(path))
    assert read.shape == image.shape
    assert np.array_equal(read, image)  # PNG is lossless
