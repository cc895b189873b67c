"""A colour DAVIS as DV records it (demosaiced frames) replays, calibrates and fits in colour."""

import dataclasses

import cv2
import numpy as np
import pytest

from davis_io.aedat.aedat4_write import write_aedat4
from davis_io.cli import main
from davis_io.colorfilter import bayer_to_rgb_code
from davis_io.emulator import EmulatedCamera
from davis_io.poses.truth import store_true_poses
from davis_io.prepare import prepare_session
from davis_io.session import Session
from davis_io.session.recorder import record
from davis_io.types import ColorFilter, Frame, Packet, SourceInfo
from seenerf.model.config import FitConfig
from seenerf.train import fit_session

SMALL = dict(frames=6, test_views=1, baseline_m=0.18, width=173, height=130, focal_px=140.0)


def _demosaiced_recording(session_dir, path):
    """The session's events and frames, the frames demosaiced as DV delivers a colour DAVIS's,
    in a file that states no colour filter."""
    with Session.open(session_dir) as session:
        frames = [session.frame(i) for i in range(session.frame_count)]
        events = session.events_by_index(0, session.event_count)
        info = SourceInfo("DAVIS346", "", session.width, session.height)  # no filter stated
    code = bayer_to_rgb_code(ColorFilter.RGGB)
    rgb = [dataclasses.replace(f, image=cv2.cvtColor(f.image, code)) for f in frames]
    write_aedat4([Packet(events=events, frames=rgb)], path, info)


def test_a_demosaiced_colour_recording_fits_in_colour(tmp_path):
    recorded = tmp_path / "recorded"
    camera = EmulatedCamera("room", color_filter=ColorFilter.RGGB, seed=3, **SMALL)
    record(camera, recorded)
    camera.write_truth(recorded)
    store_true_poses(recorded, 4)  # the poses are not what is tested here
    path = tmp_path / "dv.aedat4"
    _demosaiced_recording(recorded, path)
    replayed = tmp_path / "replayed"
    argv = ["record", "--replay", str(path), "--color-filter", "RGGB", "--out", str(replayed)]
    assert main(argv) == 0
    with Session.open(recorded) as original, Session.open(replayed) as session:
        assert session.color_filter is ColorFilter.RGGB
        assert session.frame_count == original.frame_count
        inner = (slice(1, -1), slice(1, -1))
        for index in range(session.frame_count):
            np.testing.assert_array_equal(
                session.frame(index).image[inner], original.frame(index).image[inner]
            )
        session.write_poses(4, original.poses(4))  # the same frames: the same poses
    prepare_session(replayed, 4, log=lambda line: None)  # calibrates; poses are kept
    result = fit_session(replayed, FitConfig.of(steps=3, warm_steps=10), log=lambda line: None)
    assert result.summary.steps == 3 and result.summary.skipped_steps == 0
    pngs = sorted((result.run_dir / "renders").rglob("*.png"))
    assert pngs and all(cv2.imread(str(p), cv2.IMREAD_UNCHANGED).ndim == 3 for p in pngs)


def _frames_as_three_channels(path, channels):
    """Two 16-bit frames written with three channels (``channels`` makes them from the grey
    one), in a file that states no colour filter."""
    rng = np.random.default_rng(5)
    grey = [rng.integers(0, 1024, (4, 6), dtype=np.uint16) for _ in range(2)]
    frames = [
        Frame(channels(image), 1000 * k, 1000 * k + 500, 1000 * k, 1000 * k + 600)
        for k, image in enumerate(grey)
    ]
    write_aedat4([Packet(frames=frames)], path, SourceInfo("DAVIS346", "", 6, 4))
    return grey


def test_grey_frames_saved_with_three_alike_channels_replay_as_a_mono_sensors(tmp_path):
    from davis_io.aedat import open_recording
    from davis_io.aedat.colour_frames import RawMosaicFrames

    path = tmp_path / "grey.aedat4"
    grey = _frames_as_three_channels(path, lambda image: np.stack([image] * 3, axis=-1))
    with RawMosaicFrames(open_recording(path), None) as source:
        frames = [frame for packet in source for frame in packet.frames]
    assert source.color_filter is ColorFilter.MONO
    assert [frame.image.shape for frame in frames] == [(4, 6), (4, 6)]
    for frame, image in zip(frames, grey, strict=True):
        np.testing.assert_array_equal(frame.image, image)


def test_colour_frames_in_a_file_without_a_colour_filter_ask_for_one(tmp_path):
    from davis_io.aedat import open_recording
    from davis_io.aedat.colour_frames import RawMosaicFrames
    from davis_io.errors import FormatError

    path = tmp_path / "colour.aedat4"
    _frames_as_three_channels(path, lambda image: np.stack([image, image // 2, image], axis=-1))
    with pytest.raises(FormatError, match="--color-filter"):
        with RawMosaicFrames(open_recording(path), None) as source:
            list(source)
