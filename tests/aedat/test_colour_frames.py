"""Demosaiced colour frames in a file come back as the sensor's raw mosaic, exactly."""

import datetime

import cv2
import numpy as np
import pytest

from davis_io.cli import main
from davis_io.colorfilter import BAYER_PATTERNS, bayer_to_rgb_code, mosaic_of
from davis_io.errors import UsageError
from davis_io.session import Session
from davis_io.types import ColorFilter

dv = pytest.importorskip("dv_processing")

WIDTH, HEIGHT = 346, 260


@pytest.mark.parametrize("pattern", BAYER_PATTERNS, ids=lambda p: p.value)
def test_bilinear_demosaicing_is_undone_exactly_inside_the_border(pattern):
    mosaic = np.random.default_rng(3).integers(0, 256, (6, 8), dtype=np.uint8)
    rgb = cv2.cvtColor(mosaic, bayer_to_rgb_code(pattern))
    assert not np.array_equal(rgb[..., 0], rgb[..., 1])  # really three different channels
    back = mosaic_of(rgb, pattern)
    np.testing.assert_array_equal(back[1:-1, 1:-1], mosaic[1:-1, 1:-1])
    # OpenCV copies the outermost ring from its inner neighbours: those samples are gone.
    assert not np.array_equal(back[0], mosaic[0])


def test_patterns_without_one_channel_per_pixel_are_refused():
    with pytest.raises(UsageError, match="Bayer pattern"):
        mosaic_of(np.zeros((2, 2, 3), np.uint8), ColorFilter.RGWB)


def _dv_colour_recording(path, mosaics):
    """A colour DAVIS346 file as DV writes one: BGR frames, no colour filter stated."""
    config = dv.io.MonoCameraWriter.Config("DAVIS346_COLOR")
    config.addFrameStream((WIDTH, HEIGHT))
    config.addEventStream((WIDTH, HEIGHT))
    writer = dv.io.MonoCameraWriter(str(path), config)
    for index, mosaic in enumerate(mosaics):
        bgr = cv2.cvtColor(mosaic, cv2.COLOR_BayerRGGB2BGR)
        frame = dv.Frame(10_000 * (index + 1), bgr)
        frame.exposure = datetime.timedelta(milliseconds=4)
        writer.writeFrame(frame)
    events = dv.EventStore()
    for t in range(10_000, 10_000 * (len(mosaics) + 2), 500):
        events.push_back(t, t % WIDTH, t % HEIGHT, bool(t % 1000))
    writer.writeEvents(events)
    del writer  # closes the file


def test_a_dv_colour_recording_replays_as_its_mosaic(tmp_path, capsys):
    rng = np.random.default_rng(5)
    mosaics = [rng.integers(0, 256, (HEIGHT, WIDTH), dtype=np.uint8) for _ in range(3)]
    path = tmp_path / "colour.aedat4"
    _dv_colour_recording(path, mosaics)
    refused = main(["record", "--replay", str(path), "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert refused == 1 and "--color-filter" in err and "3 channels" in err
    folder = tmp_path / "s"
    argv = ["record", "--replay", str(path), "--color-filter", "RGGB", "--out", str(folder)]
    assert main(argv) == 0
    with Session.open(folder) as session:
        assert session.color_filter is ColorFilter.RGGB and session.frame_count == 3
        for index, mosaic in enumerate(mosaics):
            inner = (slice(1, -1), slice(1, -1))
            np.testing.assert_array_equal(session.frame(index).image[inner], mosaic[inner])
    exported = tmp_path / "back.aedat4"
    assert main(["export", str(folder), "--aedat4", str(exported)]) == 0
    again = tmp_path / "again"
    assert main(["record", "--replay", str(exported), "--out", str(again)]) == 0
    with Session.open(again) as session:  # our file states the filter: no option needed
        assert session.color_filter is ColorFilter.RGGB


def test_color_filter_is_for_replays_only(capsys):
    assert main(["record", "--emulate", "room", "--color-filter", "RGGB"]) == 2
    assert "use it with --replay" in capsys.readouterr().err
