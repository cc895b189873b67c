"""The record, bins, export verbs and the session inspection, through ``seecap``'s entry point."""

import json
import signal

import h5py
import numpy as np
import pytest

from davis_io.cli import main
from davis_io.errors import DeviceError
from davis_io.session import Session
from davis_io.session.inspect import repair_session, session_report
from davis_io.session.manifest import read_manifest, write_manifest
from davis_io.session.recorder import RecordingResult

dv = pytest.importorskip("dv_processing")


@pytest.fixture
def replay_session(tmp_path, aestream_aedat4, capsys):
    folder = tmp_path / "s"
    code = main(
        [
            "record",
            "--replay",
            str(aestream_aedat4),
            "--exposure",
            "0.15",
            "--out",
            str(folder),
            "--bins",
            "4",
        ]
    )
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return folder, captured


def test_record_replay_prints_applied_and_measured_exposure(replay_session):
    folder, captured = replay_session
    assert "assumed" not in captured.out  # --exposure serves only frames that state none
    assert "measured (median) 4.773 ms" in captured.out
    assert "applied - (from the file)" in captured.out
    manifest = read_manifest(folder)
    assert manifest.source == "replay:davis346-aestream.aedat4"
    assert manifest.exposure_requested_us is None and manifest.exposure_measured_us == 4_773
    assert manifest.exposure_assumed_us is None


def test_existing_session_needs_overwrite(replay_session, aestream_aedat4, capsys):
    folder, _ = replay_session
    code = main(["record", "--replay", str(aestream_aedat4), "--out", str(folder)])
    assert code == 2 and "--overwrite" in capsys.readouterr().err  # a usage error
    code = main(["record", "--replay", str(aestream_aedat4), "--out", str(folder), "--overwrite"])
    assert code == 0


def test_no_camera_explains_what_to_do(tmp_path, monkeypatch, capsys):
    import davis_io.usb

    def no_camera(*args, **kwargs):
        raise DeviceError("no DAVIS camera found (USB 152a:841a or 152a:841b)")

    monkeypatch.setattr(davis_io.usb, "open_camera", no_camera)
    code = main(["record", "--exposure", "150ms", "--out", str(tmp_path / "s")])
    error = capsys.readouterr().err
    assert code == 1
    assert "no DAVIS camera found" in error and "--replay" in error and "--emulate" in error
    assert not (tmp_path / "s").exists()
    code = main(["record", "--out", str(tmp_path / "s")])
    assert code == 2 and "needs --exposure" in capsys.readouterr().err  # a usage error


@pytest.mark.parametrize(("stop_signal", "code"), [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_recording_stopped_by_a_signal_exits_128_plus_it(
    replay_session, monkeypatch, capsys, stop_signal, code
):
    import davis_io.capture

    folder, _ = replay_session
    result = RecordingResult(folder, read_manifest(folder), stop_signal=stop_signal)
    monkeypatch.setattr(davis_io.capture, "record_capture", lambda *a, **k: result)
    assert main(["record", "--emulate", "room", "--out", str(folder)]) == code


def test_frames_and_duration_exclude_each_other(tmp_path):
    with pytest.raises(SystemExit):
        main(["record", "--emulate", "room", "--frames", "2", "--duration", "1"])


def test_bins_verb_adds_another_b(replay_session, capsys):
    folder, _ = replay_session
    assert main(["bins", str(folder), "--bins", "6"]) == 0
    assert "/bins/b6 computed for 3 frames" in capsys.readouterr().out
    with h5py.File(folder / "session.h5", "r") as h5:
        assert h5["bins/b6/calibrated"].shape == (3, 6, 260, 346)
    assert main(["bins", str(folder), "--bins", "6"]) == 0
    assert "already stored" in capsys.readouterr().out


def test_export_opens_in_dv_processing_with_the_same_data(replay_session, tmp_path):
    folder, _ = replay_session
    out = tmp_path / "export.aedat4"
    assert main(["export", str(folder), "--aedat4", str(out)]) == 0
    recording = dv.io.MonoCameraRecording(str(out))
    batches = []
    while (batch := recording.getNextEventBatch()) is not None:
        batches.append(batch.numpy())
    events = np.concatenate(batches)
    starts = []
    while (frame := recording.getNextFrame()) is not None:
        starts.append(frame.timestamp)
    with Session.open(folder) as session:
        ours = session.events_between(0, 2**62)
        np.testing.assert_array_equal(events["timestamp"], ours["t"])
        np.testing.assert_array_equal(events["x"], ours["x"])
        np.testing.assert_array_equal(events["polarity"].astype(bool), ours["p"] > 0)
        np.testing.assert_array_equal(starts, session.frames_table().exposure_start_us)


def test_session_report_and_frame_table(replay_session):
    folder, _ = replay_session
    text = session_report(folder, frames=True, repair=False, as_json=False)
    assert "complete" in text and "4773" in text
    rows = [line for line in text.splitlines() if line.strip().split(" ")[0].isdigit()]
    assert len(rows) == 3
    document = json.loads(session_report(folder, frames=True, repair=False, as_json=True))
    assert document["session"]["frames"] == 3
    assert [row["exposure_us"] for row in document["frames"]] == [4_773] * 3
    assert all(row["events"] > 0 and not row["events_lost"] for row in document["frames"])


def test_repair_of_a_manifest_left_at_recording(replay_session):
    folder, _ = replay_session
    manifest = read_manifest(folder)
    manifest.status, manifest.stop_time_utc = "recording", ""
    write_manifest(folder, manifest)
    report = repair_session(folder)
    assert not report.rewrote_h5 and report.frames == 3
    repaired = read_manifest(folder)
    assert repaired.status == "interrupted" and repaired.stop_time_utc
    assert "nothing to repair" in repair_session(folder).describe()


def test_inspect_verb_prints_the_session_summary(replay_session, capsys):
    folder, _ = replay_session
    assert main(["inspect", str(folder)]) == 0
    out = capsys.readouterr().out
    assert "DAVIS346 serial 00000104" in out and "events_per_exposure_median" in out
