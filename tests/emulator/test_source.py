import hashlib

import cv2
import dv_processing as dv
import h5py
import numpy as np
import pytest

from davis_io.aedat import write_aedat4
from davis_io.emulator import EmulatedCamera
from davis_io.emulator.aps import ApsSettings, expose
from davis_io.emulator.response import apply_response
from davis_io.errors import SessionError, UsageError
from davis_io.session import Session
from davis_io.session.recorder import record as record_session
from davis_io.session.truth import load_truth, save_truth
from davis_io.types import ColorFilter, PacketSource, TriggerKind

SMALL = dict(width=64, height=48, focal_px=52.0, frames=2, test_views=2, exposure_us=20_000)


def record(**settings):
    camera = EmulatedCamera("room", **{**SMALL, **settings})
    with camera:
        packets = list(camera)
    return camera, packets


@pytest.fixture(scope="module")
def small():
    return record(seed=7)


def digest(packets):
    hasher = hashlib.sha256()
    for packet in packets:
        for name in packet.events.dtype.names:  # fields, not records: padding is undefined
            hasher.update(packet.events[name].tobytes())
        hasher.update(packet.triggers.tobytes())
        for frame in packet.frames:
            hasher.update(frame.image.tobytes())
            hasher.update(repr(frame).encode())
    return hasher.hexdigest()


def test_is_a_packet_source_with_davis346_info(small):
    camera, _ = small
    assert isinstance(camera, PacketSource)
    assert camera.info.camera == "DAVIS346"
    assert camera.info.origin == "emulator:room"
    assert camera.info.color_filter is ColorFilter.RGGB
    assert (camera.info.width, camera.info.height) == (64, 48)


def test_packets_are_time_ordered_with_frames_after_their_readout(small):
    camera, packets = small
    events = np.concatenate([p.events for p in packets])
    assert len(events) > 1000
    assert np.all(np.diff(events["t"]) >= 0)
    assert events["x"].max() < 64 and events["y"].max() < 48
    assert set(np.unique(events["p"])) == {-1, 1}
    frames = [(i, f) for i, p in enumerate(packets) for f in p.frames]
    assert len(frames) == 2
    config = camera.config
    for number, (packet_index, frame) in enumerate(frames):
        # Readout (8 ms) before and after a 20 ms exposure; frames every 70 ms from 20 ms.
        start = config.lead_us + number * config.frame_interval_us
        assert (frame.readout_start_us, frame.exposure_start_us) == (start, start + 8000)
        assert (frame.exposure_end_us, frame.readout_end_us) == (start + 28_000, start + 36_000)
        assert frame.image.shape == (48, 64) and frame.image.dtype == np.uint16
        assert frame.bit_depth == 10 and frame.image.max() <= 1023
        # Yielded in the packet whose time span holds the end of readout.
        packet_start = packet_index * config.packet_us
        assert packet_start <= frame.readout_end_us < packet_start + config.packet_us
    imu = np.concatenate([p.imu for p in packets])
    assert len(imu) == config.end_us // 1000 + 1 and set(np.diff(imu["t"])) == {1000}
    triggers = np.concatenate([p.triggers for p in packets])
    assert np.all(np.diff(triggers["t"]) >= 0)
    assert triggers["kind"][:4].tolist() == [
        TriggerKind.APS_FRAME_START,
        TriggerKind.APS_EXPOSURE_START,
        TriggerKind.APS_EXPOSURE_END,
        TriggerKind.APS_FRAME_END,
    ]
    # Events keep coming between exposures (readout and frame gap).
    gap = (events["t"] > frames[0][1].exposure_end_us) & (
        events["t"] < frames[1][1].exposure_start_us
    )
    assert gap.sum() > 100


def test_same_seed_same_bytes_other_seed_other_bytes(small):
    _, packets = small
    assert digest(record(seed=7)[1]) == digest(packets)
    assert digest(record(seed=8)[1]) != digest(packets)


def test_frame_is_the_response_of_the_weighted_subframe_sum():
    camera, packets = record(seed=1, aps_noise=False)
    frame = next(f for p in packets for f in p.frames)
    truth = camera.truth
    subframes = np.stack([camera.sensor_image(c2w) for c2w in truth.train_c2w[0]])
    assert truth.train_time_us[0, 0] == frame.exposure_start_us
    assert truth.train_time_us[0, -1] == frame.exposure_end_us
    weights = np.r_[0.5, np.ones(15), 0.5] / 16
    blurred = np.tensordot(weights, subframes.astype(np.float64), axes=1)
    expected = np.round(apply_response("reinhard_gamma", blurred) * 1023)  # gain * exposure = 1
    np.testing.assert_array_equal(frame.image, expected)
    assert np.array_equal(frame.image, expose(subframes, 0.02, ApsSettings(gain_per_s=50.0), None))
    # The blur is real: the blurred frame differs from the mid-exposure sharp frame.
    sharp = np.round(apply_response("reinhard_gamma", subframes[8]) * 1023)
    assert np.abs(sharp - frame.image).mean() > 2


def test_truth_layout_and_round_trip(small, tmp_path):
    camera, _ = small
    truth = camera.truth
    assert truth.train_time_us.shape == (2, 17) and truth.train_time_us.dtype == np.int64
    assert truth.train_c2w.shape == (2, 17, 4, 4)
    assert (
        truth.train_sharp_hdr.shape == (2, 48, 64, 3) and truth.train_sharp_hdr.dtype == np.float32
    )
    assert truth.test_c2w.shape == (2, 4, 4)
    assert truth.test_hdr.shape == (2, 48, 64, 3)
    assert truth.test_ldr.shape == (2, 5, 48, 64, 3) and truth.test_ldr.dtype == np.uint8
    np.testing.assert_allclose(truth.test_exposures_s, np.array([1 / 16, 1 / 4, 1, 4, 16]) * 0.02)
    np.testing.assert_allclose(truth.intrinsics, [52.0, 52.0, 31.5, 23.5])
    # LDR at x1 is the response of the sharp HDR (gain * exposure = 1 at the training exposure).
    np.testing.assert_array_equal(
        truth.test_ldr[:, 2], np.round(apply_response("reinhard_gamma", truth.test_hdr) * 255)
    )
    assert np.all(truth.test_ldr[:, 0] <= truth.test_ldr[:, 4])
    folder = save_truth(truth, tmp_path / "truth")
    assert (folder / "test" / "hdr" / "001.exr").exists()
    assert (folder / "test" / "ldr" / "x1_16" / "000.png").exists()
    back = load_truth(tmp_path)  # a session folder holding truth/ works too
    for name, value in vars(truth).items():
        if isinstance(value, np.ndarray):
            np.testing.assert_array_equal(getattr(back, name), value)
        else:
            assert getattr(back, name) == value
    with pytest.raises(SessionError, match="no ground truth"):
        load_truth(tmp_path / "nowhere")


def test_monochrome_sensor_gives_one_channel_truth(tmp_path):
    camera = EmulatedCamera("lamp", **{**SMALL, "frames": 1, "test_views": 1}, color_filter="mono")
    truth = camera.truth
    assert truth.test_hdr.shape == (1, 48, 64, 1) and truth.test_ldr.shape == (1, 5, 48, 64, 1)
    assert camera.info.color_filter is ColorFilter.MONO
    folder = save_truth(truth, tmp_path / "truth")
    png = cv2.imread(str(folder / "test" / "ldr" / "x4" / "000.png"), cv2.IMREAD_UNCHANGED)
    np.testing.assert_array_equal(png, truth.test_ldr[0, 3, ..., 0])
    assert load_truth(folder).color_filter is ColorFilter.MONO


def test_an_auto_exposure_shortens_the_frames_it_darkens():
    # Half and quarter of 20 ms in turn, at the gain of 20 ms: each frame gathers its share.
    camera, packets = record(seed=1, aps_noise=False, frames=3, exposure_steps=(1.0, 0.5, 0.25))
    frames = [f for p in packets for f in p.frames]
    lengths = [f.exposure_end_us - f.exposure_start_us for f in frames]
    assert lengths == [20_000, 10_000, 5_000]
    assert camera.truth.exposure_us == 20_000  # the gain's exposure, the test views'
    for index, (frame, share) in enumerate(zip(frames, (1.0, 0.5, 0.25), strict=True)):
        times = camera.truth.train_time_us[index]
        subframes = np.stack([camera.sensor_image(c2w) for c2w in camera.trajectory.c2w(times)])
        settings = ApsSettings(gain_per_s=50.0)
        expected = expose(subframes, 0.02 * share, settings, None)
        np.testing.assert_array_equal(frame.image, expected)
    with pytest.raises(UsageError, match="exposure steps"):
        EmulatedCamera("room", exposure_steps=(1.0, 1.5))


def test_from_config_reproduces_the_camera(small):
    camera, packets = small
    again = EmulatedCamera.from_config(camera.config)
    assert again.config == camera.config
    assert digest(list(again)) == digest(packets)


def test_bad_settings_are_refused():
    with pytest.raises(UsageError, match="frame interval"):
        EmulatedCamera("room", exposure_us=100_000, frame_interval_us=100_000)
    with pytest.raises(UsageError, match="DVS preset"):
        EmulatedCamera("room", dvs_preset="loud")
    with pytest.raises(UsageError, match="unknown emulator scene"):
        EmulatedCamera("garden")
    with pytest.raises(UsageError, match="colour filter"):
        EmulatedCamera("room", color_filter="CMYK")
    with pytest.raises(UsageError, match="must not be negative"):
        EmulatedCamera("room", shake=-1.0)
    with pytest.raises(UsageError, match="camera model 'DAVIS128' is not one of DAVIS346"):
        EmulatedCamera("room", model="DAVIS128")
    with pytest.raises(UsageError, match="a DAVIS240 has 240x180 pixels at most"):
        EmulatedCamera("room", model="DAVIS240", color_filter=ColorFilter.MONO)  # 346x260
    with pytest.raises(UsageError, match="a DAVIS240 is mono"):
        EmulatedCamera("room", model="DAVIS240", width=240, height=180)  # RGGB by default


def test_aedat4_opens_in_dv_processing_with_the_same_content(small, tmp_path):
    camera, packets = small
    path = write_aedat4(packets, tmp_path / "room.aedat4", camera.info)
    recording = dv.io.MonoCameraRecording(str(path))
    assert tuple(recording.getEventResolution()) == (64, 48)
    theirs = []
    while (batch := recording.getNextEventBatch()) is not None:
        theirs.append(batch.numpy())
    theirs = np.concatenate(theirs)
    ours = np.concatenate([p.events for p in packets])
    np.testing.assert_array_equal(theirs["timestamp"], ours["t"])
    np.testing.assert_array_equal(theirs["x"], ours["x"])
    np.testing.assert_array_equal(theirs["y"], ours["y"])
    np.testing.assert_array_equal(np.where(theirs["polarity"], 1, -1), ours["p"])
    for frame in [f for p in packets for f in p.frames]:
        stored = recording.getNextFrame()
        np.testing.assert_array_equal(stored.image, frame.image << 6)  # 10 bits left-aligned
        assert stored.timestamp == frame.exposure_start_us


def test_truth_file_missing_a_field_is_a_clear_error(small, tmp_path):
    camera, _ = small
    folder = save_truth(camera.truth, tmp_path / "truth")
    with h5py.File(folder / "truth.h5", "a") as h5:
        del h5["test/ldr"]
    with pytest.raises(SessionError, match="missing"):
        load_truth(folder)
    (folder / "truth.h5").write_bytes(b"not hdf5")
    with pytest.raises(SessionError, match="cannot be read"):
        load_truth(folder)


def test_truth_gives_the_true_pose_at_any_time(small):
    camera, _ = small
    truth = camera.truth
    assert truth.path_time_us[0] == 0 and set(np.diff(truth.path_time_us)) == {1000}
    # Interpolation error: about dt**2 / 8 * angular acceleration ~ 3e-6 rad for 1 ms samples.
    np.testing.assert_allclose(truth.c2w_at(truth.train_time_us[1]), truth.train_c2w[1], atol=1e-5)
    between = np.array([12_345, 67_891])  # not on the 1 ms grid
    np.testing.assert_allclose(truth.c2w_at(between), camera.trajectory.c2w(between), atol=1e-5)
    # Not trivially close: the pose moves by far more than that within a millisecond.
    moved = camera.trajectory.c2w(between + 500)
    assert np.abs(moved - camera.trajectory.c2w(between)).max() > 1e-4


def test_a_session_names_the_camera_it_was_recorded_with(tmp_path):
    original = EmulatedCamera("lamp", seed=3, color_filter=ColorFilter.MONO, **SMALL)
    recorded = record_session(original, tmp_path / "s")
    original.write_truth(recorded.folder)
    again = EmulatedCamera.of_session(recorded.folder)
    with Session.open(recorded.folder) as session:
        frame = session.frame(0)
    assert again.config == original.config
    # The recorded frame is the noise-free one plus sensor noise: close, not equal.
    clean = again.noise_free_frame(frame).astype(float)
    difference = np.abs(frame.image - clean)
    assert 0 < difference.mean() < 0.05 * clean.mean()
    with pytest.raises(SessionError, match="no ground truth"):
        EmulatedCamera.of_session(tmp_path / "nowhere")
    with h5py.File(recorded.folder / "truth" / "truth.h5", "a") as h5:
        del h5.attrs["camera"]  # a truth written before it said how it was recorded
    with pytest.raises(UsageError, match="does not say how it was recorded"):
        EmulatedCamera.of_session(recorded.folder)


def test_the_truth_of_linear_frames_states_their_noise_for_white_box_fits():
    # The named linear response: slope 0.3, 3000 electrons per unit, 4 electrons read noise:
    # gain 0.3 / 3000 = 1e-4, floor (0.3 * 4 / 3000)^2 + (1/1023)^2 / 12 = 1.6e-7 + 7.963e-8.
    linear = EmulatedCamera("room", **{**SMALL, "response": "linear"}).truth
    calibration = linear.sensor_calibration()
    assert calibration.noise_gain == pytest.approx(1e-4, rel=1e-6)
    assert calibration.noise_floor == pytest.approx(2.3963e-7, rel=1e-4)
    quiet = EmulatedCamera("room", **{**SMALL, "response": "linear", "aps_noise": False}).truth
    assert quiet.sensor_calibration().noise_gain == 0  # only the rounding is left
    film = EmulatedCamera("room", **{**SMALL, "response": "film"}).truth.sensor_calibration()
    assert film.noise_gain == film.noise_floor == 0  # not a line in the value: not stated
