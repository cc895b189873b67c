"""Recording the built-in emulator end to end, with its ground truth beside the session."""

import pytest

from davis_io.capture import CaptureRequest, record_capture
from davis_io.session import Session


@pytest.mark.slow
def test_emulated_recording_keeps_exposure_frames_and_truth(tmp_path):
    request = CaptureRequest(exposure_us=20_000, frames=2, emulate="room")
    result = record_capture(request, tmp_path / "s", bins=4)
    assert result.status == "complete"
    manifest = result.manifest
    assert manifest.source == "emulator:room" and manifest.frame_count == 2
    assert manifest.exposure_requested_us == manifest.exposure_measured_us == 20_000
    with Session.open(tmp_path / "s") as session:
        assert session.truth_dir == tmp_path / "s" / "truth"
        assert session.color_filter.is_color
        bins = session.bins(4)
        assert (bins.event_count > 0).all()
        # Frame interval: exposure + 50 ms (the emulator's and the camera's default).
        starts = session.frames_table().exposure_start_us
        assert starts[1] - starts[0] == 70_000


def test_an_auto_exposure_recording_keeps_each_frames_exposure(tmp_path):
    from davis_io.session.inspect import session_report

    request = CaptureRequest(
        exposure_us=20_000, frames=3, emulate="room", exposure_steps=(1.0, 0.5, 0.25)
    )
    result = record_capture(request, tmp_path / "s", bins=4)
    assert result.manifest.exposure_measured_us == 10_000  # the median frame's
    with Session.open(tmp_path / "s") as session:
        assert session.frames_table().exposure_us.tolist() == [20_000, 10_000, 5_000]
    report = session_report(tmp_path / "s", frames=False, repair=False, as_json=False)
    assert "5000..20000 (an auto exposure)" in report


def test_an_emulated_davis240_records_its_whole_mono_array(tmp_path):
    from davis_io.emulator import EmulatedCamera

    request = CaptureRequest(
        exposure_us=20_000, frames=2, emulate="room", model="DAVIS240", sensor="random", seed=10
    )
    result = record_capture(request, tmp_path / "s", bins=4)
    manifest = result.manifest
    assert (manifest.camera, manifest.width, manifest.height) == ("DAVIS240", 240, 180)
    with Session.open(tmp_path / "s") as session:
        # Seed 10 draws an RGGB sensor for a DAVIS346 (the blind benchmark's room-s10); a
        # DAVIS240 was made mono only, so its drawn sensor is mono.
        assert not session.color_filter.is_color
        assert session.frames_table().exposure_us.tolist() == [20_000, 20_000]
        assert session.bins(4).event_count.min() > 0
    # The truth remembers the model: the same camera is made again from it.
    again = EmulatedCamera.of_session(tmp_path / "s")
    assert (again.config.model, again.config.width, again.config.height) == ("DAVIS240", 240, 180)
