"""A colour DAVIS as DV records it (demosaiced frames) replays, calibrates and fits in colour."""

import dataclasses
import shutil

import cv2
import numpy as np

from davis_io.aedat.aedat4_write import write_aedat4
from davis_io.cli import main
from davis_io.colorfilter import bayer_to_rgb_code
from davis_io.emulator import EmulatedCamera
from davis_io.prepare import prepare_session
from davis_io.session import Session
from davis_io.session.recorder import record
from davis_io.types import ColorFilter, Packet, SourceInfo
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
    record(EmulatedCamera("room", color_filter=ColorFilter.RGGB, seed=3, **SMALL), recorded)
    prepare_session(recorded, 4, log=lambda line: None)  # calibration and COLMAP poses
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
    shutil.copytree(recorded / "colmap", replayed / "colmap")
    prepare_session(replayed, 4, log=lambda line: None)  # calibrates; poses are kept
    result = fit_session(replayed, FitConfig.of(steps=3, warm_steps=10), log=lambda line: None)
    assert result.summary.steps == 3 and result.summary.skipped_steps == 0
    pngs = sorted((result.run_dir / "renders").rglob("*.png"))
    assert pngs and all(cv2.imread(str(p), cv2.IMREAD_UNCHANGED).ndim == 3 for p in pngs)
