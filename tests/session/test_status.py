"""Per-frame warnings, the status line and the preview image."""

import numpy as np

from davis_io.bins import bin_exposure
from davis_io.session.manifest import DropCounters
from davis_io.session.preview import event_image, preview_image, write_preview
from davis_io.session.status import RecordingStatus, format_status_line, frame_warnings
from davis_io.types import EVENT_DTYPE, Frame


def frame_of(image, bit_depth=10):
    return Frame(
        image=image,
        exposure_start_us=0,
        exposure_end_us=150_000,
        readout_start_us=0,
        readout_end_us=160_000,
        bit_depth=bit_depth,
    )


def bins_with(counts_per_pixel, width=10, height=10, b=1):
    """``b`` bins where the first ``len(counts_per_pixel)`` pixels fired that many ON events."""
    times, pixels = [], []
    for pixel, count in enumerate(counts_per_pixel):
        times += list(range(count))
        pixels += [pixel] * count
    order = np.argsort(times, kind="stable")
    events = np.zeros(len(times), EVENT_DTYPE)
    events["t"] = np.array(times)[order]
    events["x"] = np.array(pixels, dtype=int)[order] % width
    events["y"] = np.array(pixels, dtype=int)[order] // width
    events["p"] = 1
    return bin_exposure(events, 0, 150_000, b, width, height)


def test_a_good_frame_has_no_warning():
    image = np.full((10, 10), 500, np.uint16)
    assert frame_warnings(0, frame_of(image), bins_with([1, 2, 1])) == []


def test_saturated_and_underexposed_fractions():
    image = np.full((10, 10), 500, np.uint16)
    image[:3] = 1023  # 30 % at full scale (> 25 %)
    (warning,) = frame_warnings(7, frame_of(image), bins_with([1]))
    assert warning.startswith("frame 7 (exposure 150.00 ms): 30% saturated")
    dark = np.full((10, 10), 3, np.uint8)  # 3/255 = 1.2 % of full scale: underexposed
    (warning,) = frame_warnings(0, frame_of(dark, bit_depth=8), bins_with([1]))
    assert "100% underexposed" in warning


def test_no_events():
    image = np.full((10, 10), 500, np.uint16)
    (warning,) = frame_warnings(0, frame_of(image), bins_with([]))
    assert "no events during the exposure" in warning


def test_blur_is_judged_against_the_bin_count():
    image = np.full((10, 10), 500, np.uint16)
    # b = 1: the limit is 4 events per pixel. 11 of 100 pixels fired 5 (> 10 % above it): warn.
    (warning,) = frame_warnings(0, frame_of(image), bins_with([5] * 11))
    assert "blur too strong for b=1 bins (11% of pixels fired > 4 events)" in warning
    # 10 % above the limit, or any number exactly at it, is not more than 10 %: quiet.
    assert frame_warnings(0, frame_of(image), bins_with([5] * 10 + [4] * 50)) == []
    # b = 4: the limit is 4 * 4 = 16 events; 16 everywhere is fine, 17 at 11 pixels is not.
    assert frame_warnings(0, frame_of(image), bins_with([16] * 100, b=4)) == []
    (warning,) = frame_warnings(0, frame_of(image), bins_with([17] * 11 + [16] * 89, b=4))
    assert "blur too strong for b=4 bins (11% of pixels fired > 16 events)" in warning


def test_status_line():
    status = RecordingStatus(
        elapsed_s=12.34,
        frames=61,
        events=10,
        events_per_s=1.2e6,
        bytes_written=45_100_000,
        queue_fill=0.03,
        drops=DropCounters(source_events=5, queue_events=2, queue_frames=1),
        exposure_measured_us=150_000,
    )
    line = format_status_line(status)
    for part in (
        "12.3 s",
        "61 frames",
        "1.20 Mev/s",
        "45.1 MB",
        "queue 3%",
        "drops 7 ev 1 fr",
        "exposure 150.00 ms",
    ):
        assert part in line
    assert "exposure -" in format_status_line(RecordingStatus())


def test_preview_image_and_atomic_write(tmp_path):
    import cv2

    counts = np.zeros((4, 5), np.int32)
    counts[1, 2], counts[3, 4] = 2, -1
    colours = event_image(counts)
    assert tuple(colours[0, 0]) == (255, 255, 255)
    assert colours[1, 2, 2] > 200 and colours[1, 2, 0] < 100  # ON: red (BGR)
    assert colours[3, 4, 0] > 200 and colours[3, 4, 2] < 100  # OFF: blue
    image = preview_image(np.full((4, 5), 1023, np.uint16), 10, counts)
    assert image.shape == (4, 5 + 4 + 5, 3) and image[0, 0, 0] == 255
    path = tmp_path / "preview.png"
    write_preview(path, image)
    np.testing.assert_array_equal(cv2.imread(str(path)), image)
    assert [p.name for p in tmp_path.iterdir()] == ["preview.png"]
