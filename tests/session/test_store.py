"""The session reader: frames, event windows, bins on demand, poses, manifest."""

import json

import h5py
import numpy as np
import pytest
from session_fakes import (
    EXPOSURE_END_US,
    EXPOSURE_START_US,
    HEIGHT,
    WIDTH,
    ListSource,
    synthetic_packets,
)

from davis_io.bins import bin_exposure
from davis_io.errors import SessionError
from davis_io.session import Session, SessionManifest, SessionPoses
from davis_io.session.recorder import record


@pytest.fixture
def recorded(tmp_path):
    packets = synthetic_packets(4, seed=3)
    record(ListSource(packets), tmp_path / "s", bins=4, exposure_us=4_000)
    events = np.concatenate([p.events for p in packets])
    return tmp_path / "s", events


def test_frames_and_timestamps_round_trip(recorded):
    folder, _ = recorded
    with Session.open(folder) as session:
        assert session.frame_count == 4
        assert (session.width, session.height) == (WIDTH, HEIGHT)
        table = session.frames_table()
        np.testing.assert_array_equal(table.exposure_start_us, [1_000, 11_000, 21_000, 31_000])
        np.testing.assert_array_equal(table.exposure_us, [4_000] * 4)
        assert not table.events_lost.any()
        frame = session.frame(-1)
        assert frame.exposure_start_us == 31_000 and frame.readout_end_us == 38_000
        assert frame.image.dtype == np.uint16 and int(frame.image[0, 0]) == 503
        assert frame.bit_depth == 10
        with pytest.raises(SessionError, match="out of range"):
            session.frame(4)


def test_events_between_includes_both_ends(recorded):
    folder, events = recorded
    with Session.open(folder) as session:
        assert session.event_count == len(events)
        t0, t1 = int(events["t"][100]), int(events["t"][900])
        window = session.events_between(t0, t1)
        expected = events[(events["t"] >= t0) & (events["t"] <= t1)]
        np.testing.assert_array_equal(window, expected)
        assert len(session.events_between(10**12, 10**12 + 5)) == 0


def test_record_time_bins_equal_direct_binning(recorded):
    folder, events = recorded
    with Session.open(folder) as session:
        bins = session.bins(4)
        for index in range(4):
            start = index * 10_000 + EXPOSURE_START_US
            direct = bin_exposure(events, start, index * 10_000 + EXPOSURE_END_US, 4, WIDTH, HEIGHT)
            np.testing.assert_array_equal(bins.raw[index], direct.raw)
            np.testing.assert_array_equal(bins.calibrated[index], direct.calibrated)
            np.testing.assert_array_equal(bins.split_us[index], direct.split_us)
            assert bins.event_count[index] == direct.event_count > 0


def test_bins_for_another_b_are_computed_once_and_stored(recorded):
    folder, events = recorded
    with Session.open(folder) as session:
        assert not session.has_bins(6)
        six = session.bins(6)
        assert six.raw.shape == (4, 6, HEIGHT, WIDTH)
        direct = bin_exposure(events, 21_000, 25_000, 6, WIDTH, HEIGHT)
        np.testing.assert_array_equal(six.calibrated[2], direct.calibrated)
    with h5py.File(folder / "session.h5", "r") as h5:
        assert h5["bins/b6/raw"].shape == (4, 6, HEIGHT, WIDTH)
    with Session.open(folder) as session:
        assert session.stored_bins() == [4, 6]


def test_poses_round_trip_and_shape_check(recorded):
    folder, _ = recorded
    rng = np.random.default_rng(0)
    poses = SessionPoses(
        c2w=rng.normal(size=(4, 5, 4, 4)),
        registered=rng.random((4, 5)) > 0.3,
        intrinsics=np.array([300.0, 301.0, 173.0, 130.0]),
        distortion=np.array([0.01, -0.002]),
        bounds=np.array([0.5, 9.0]),
    )
    with Session.open(folder) as session:
        assert session.poses(4) is None
        session.write_poses(4, poses)
        loaded = session.poses(4)
        for name in ("c2w", "registered", "intrinsics", "distortion", "bounds"):
            np.testing.assert_array_equal(getattr(loaded, name), getattr(poses, name))
        with pytest.raises(SessionError, match="c2w"):
            session.write_poses(6, poses)


def test_truth_dir(recorded):
    folder, _ = recorded
    with Session.open(folder) as session:
        assert session.truth_dir is None
    (folder / "truth").mkdir()
    with Session.open(folder) as session:
        assert session.truth_dir == folder / "truth"


def test_manifest_fields_and_bad_manifests(recorded, tmp_path):
    folder, events = recorded
    values = json.loads((folder / "session.json").read_text())
    assert values["format_version"] == 1 and values["status"] == "complete"
    assert values["exposure_requested_us"] == 4_000 and values["exposure_measured_us"] == 4_000
    assert values["event_count"] == len(events) and values["frame_count"] == 4
    assert values["b"] == 4 and values["source"] == "emulator:test"
    values["format_version"] = 2
    with pytest.raises(SessionError, match="format version 2"):
        SessionManifest.from_json(json.dumps(values))
    with pytest.raises(SessionError, match="not valid JSON"):
        SessionManifest.from_json("{")
    with pytest.raises(SessionError, match="not a session folder"):
        Session.open(tmp_path / "nowhere")


def test_manifest_json_keeps_device_facts_json_lacks():
    from davis_io.types import ColorFilter

    manifest = SessionManifest(
        camera="DAVIS346",
        serial="1",
        width=346,
        height=260,
        color_filter="mono",
        source="usb",
        b=4,
        device_config={"filter": ColorFilter.RGGB, "gain": np.int64(3)},
    )
    again = SessionManifest.from_json(manifest.to_json())
    assert again.device_config == {"filter": "RGGB", "gain": 3}
    assert again == SessionManifest.from_json(again.to_json())
