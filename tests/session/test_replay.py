"""Recording the real DAVIS346 fixture: frames, windows and counts against dv-processing."""

import datetime

import numpy as np
import pytest

from davis_io.aedat import open_recording
from davis_io.bins import bin_exposure
from davis_io.session import Session
from davis_io.session.recorder import record
from davis_io.types import EVENT_DTYPE

dv = pytest.importorskip("dv_processing")


def read_with_dv(path):
    """Events as (t, x, y, polarity) and frame windows (start, end) read by dv-processing."""
    recording = dv.io.MonoCameraRecording(str(path))
    batches = []
    while (batch := recording.getNextEventBatch()) is not None:
        batches.append(batch.numpy())
    windows, images = [], []
    while (frame := recording.getNextFrame()) is not None:
        # dv-processing gives a frame's timestamp as its exposure start (fixtures README).
        exposure_us = frame.exposure // datetime.timedelta(microseconds=1)
        windows.append((frame.timestamp, frame.timestamp + exposure_us))
        images.append(frame.image)
    return np.concatenate(batches), windows, images


@pytest.fixture
def replayed(tmp_path, aestream_aedat4):
    folder = tmp_path / "s"
    result = record(open_recording(aestream_aedat4), folder, bins=4, exposure_us=150_000)
    events, windows, images = read_with_dv(aestream_aedat4)
    return folder, result, events, windows, images


def test_three_frames_with_the_fixture_windows(replayed):
    folder, result, _, windows, images = replayed
    assert result.status == "complete"
    with Session.open(folder) as session:
        assert session.frame_count == 3
        table = session.frames_table()
        np.testing.assert_array_equal(table.exposure_start_us, [w[0] for w in windows])
        np.testing.assert_array_equal(table.exposure_end_us, [w[1] for w in windows])
        # Fixture facts: exposure starts 40 ms apart, 4,773 µs each.
        np.testing.assert_array_equal(np.diff(table.exposure_start_us), [40_000, 40_000])
        assert set(table.exposure_us.tolist()) == {4_773}
        for index, image in enumerate(images):
            np.testing.assert_array_equal(session.frame(index).image, image.reshape(260, 346))
    assert result.manifest.exposure_measured_us == 4_773
    assert result.manifest.exposure_requested_us == 150_000


def test_window_event_counts_match_dv_processing(replayed):
    folder, _, events, windows, _ = replayed
    t = events["timestamp"]
    expected = [int(np.count_nonzero((t >= start) & (t <= end))) for start, end in windows]
    with Session.open(folder) as session:
        assert session.event_count == len(events) == 117_667
        np.testing.assert_array_equal(session.bins(4).event_count, expected)
        assert min(expected) > 0


def test_bins_of_a_fixture_frame_match_dv_events(replayed):
    folder, _, events, windows, _ = replayed
    ours = np.zeros(len(events), dtype=EVENT_DTYPE)
    ours["t"], ours["x"], ours["y"] = events["timestamp"], events["x"], events["y"]
    ours["p"] = np.where(events["polarity"] > 0, 1, -1)
    start, end = windows[1]
    direct = bin_exposure(ours, start, end, 4, 346, 260)
    with Session.open(folder) as session:
        bins = session.bins(4)
        np.testing.assert_array_equal(bins.raw[1], direct.raw)
        np.testing.assert_array_equal(bins.split_us[1], direct.split_us)
        # The signed counts per pixel add up to the window's ON minus OFF events.
        window = (ours["t"] >= start) & (ours["t"] <= end)
        assert int(bins.raw[1].sum()) == int(ours["p"][window].sum())
