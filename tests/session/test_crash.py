"""A recorder killed with SIGKILL mid-write leaves a readable session that repair makes normal."""

import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from davis_io.session import Session
from davis_io.session.inspect import repair_session, session_report

RECORD_FOREVER = Path(__file__).with_name("record_forever.py")


def record_then_signal(
    folder: Path, min_frames: int, signal_number: int, *options: str
) -> tuple[int, int]:
    """Run the endless recorder in a subprocess; signal it once it reported ``min_frames``.

    Returns:
        The frames reported before the signal and the process return code.
    """
    process = subprocess.Popen(
        [sys.executable, str(RECORD_FOREVER), str(folder), *options],
        stdout=subprocess.PIPE,
        text=True,
    )
    reported = 0
    try:
        for line in process.stdout:
            reported, events = int(line.split()[1]), int(line.split()[3])
            if reported >= min_frames and events > 0:
                break
    finally:
        process.send_signal(signal_number)
        process.wait(timeout=60)
    return reported, process.returncode


def test_killed_recording_opens_and_repairs(tmp_path):
    folder = tmp_path / "s"
    reported, code = record_then_signal(folder, 20, signal.SIGKILL)  # no cleanup runs
    assert code == -signal.SIGKILL
    with Session.open(folder) as session:
        assert session.needs_repair
        assert session.manifest.status == "recording"
        frames = session.frame_count
        # Frames are counted only after they were flushed, so none reported can be missing.
        assert frames >= reported >= 20
        table = session.frames_table()
        np.testing.assert_array_equal(table.exposure_start_us, np.arange(frames) * 10_000 + 1_000)
        counts = session.window_event_counts()
        for index in (0, frames - 1):
            assert int(session.frame(index).image[0, 0]) == index % 1000
            window = session.events_between(
                int(table.exposure_start_us[index]), int(table.exposure_end_us[index])
            )
            assert counts[index] == len(window) > 0
        events = session.event_count
    report = repair_session(folder)
    assert report.rewrote_h5 and report.frames == frames and report.events == events
    with Session.open(folder) as session:
        assert not session.needs_repair
        assert session.manifest.status == "interrupted"
        assert session.frame_count == frames and session.event_count == events
        assert session.bins(2).raw.shape[0] == frames  # writable again
    text = session_report(folder, repair=True, frames=True, as_json=False)
    assert "nothing to repair" in text and "interrupted" in text


def test_an_unrepaired_session_is_refused_before_any_work(tmp_path, capsys):
    from davis_io.cli import main

    folder = tmp_path / "s"
    record_then_signal(folder, 5, signal.SIGKILL)
    for verb in ("calibrate", "poses"):
        assert main([verb, str(folder)]) == 1
        err = capsys.readouterr().err
        assert f"seecap inspect {folder} --repair" in err and "Traceback" not in err
    assert not (folder / "colmap").exists()  # nothing was started


@pytest.mark.parametrize(
    ("signal_number", "reason"), [(signal.SIGINT, "Ctrl-C"), (signal.SIGTERM, "SIGTERM")]
)
def test_ctrl_c_and_sigterm_close_the_session_interrupted(tmp_path, signal_number, reason):
    folder = tmp_path / "s"
    reported, code = record_then_signal(folder, 5, signal_number)
    assert code == 0  # record() returned normally after the signal
    with Session.open(folder) as session:
        assert not session.needs_repair
        assert session.manifest.status == "interrupted"
        assert session.manifest.stop_reason == f"interrupted ({reason})"
        assert session.frame_count >= reported >= 5
        assert session.manifest.frame_count == session.frame_count


def test_killed_before_the_first_frame(tmp_path):
    folder = tmp_path / "s"
    _, code = record_then_signal(folder, 0, signal.SIGKILL, "--no-frames")
    assert code == -signal.SIGKILL
    with Session.open(folder) as session:
        assert session.needs_repair and session.frame_count == 0
        assert len(session.frames_table().exposure_us) == 0
    report = repair_session(folder)
    assert report.rewrote_h5 and report.frames == 0
    with Session.open(folder) as session:
        assert session.event_count == report.events
        assert session.bins(4).raw.shape == (0, 4, 6, 8)
        assert session.manifest.status == "interrupted"
