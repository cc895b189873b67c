"""A disk that fills while recording or adding bins: a readable session, one line, exit 1."""

import itertools
import os
import shutil
import subprocess
import sys
from collections import namedtuple
from pathlib import Path

import pytest
from session_fakes import ListSource, endless_packets

import davis_io.session.writer as writer_module
from davis_io.cli import main
from davis_io.errors import SessionError
from davis_io.session import Session
from davis_io.session.inspect import repair_session
from davis_io.session.recorder import RecordingError, record

Usage = namedtuple("Usage", "total used free")


def _disk_filling_after(monkeypatch, checks: int) -> None:
    """The free space reported drops below the margin after ``checks`` checks."""
    seen = []
    real = shutil.disk_usage

    def disk_usage(path):
        seen.append(path)
        usage = real(path)
        free = usage.free if len(seen) <= checks else writer_module.MIN_FREE_BYTES - 1
        return Usage(usage.total, usage.total - free, free)

    monkeypatch.setattr(writer_module.shutil, "disk_usage", disk_usage)


def test_a_recording_stops_before_the_disk_is_full(tmp_path, monkeypatch):
    _disk_filling_after(monkeypatch, 40)
    with pytest.raises(RecordingError, match=r"is full \(\d+ MB free; a recording stops") as caught:
        record(ListSource(endless_packets(True)), tmp_path / "s")
    monkeypatch.undo()
    result = caught.value.result
    with Session.open(tmp_path / "s") as session:
        assert not session.needs_repair
        assert session.manifest.status == "interrupted"
        assert "is full" in session.manifest.stop_reason
        assert session.frame_count == result.manifest.frame_count > 0
        assert session.event_count == result.manifest.event_count > 0
        assert session.bins(4).raw.shape[0] == session.frame_count


def test_bins_on_a_full_disk_are_not_listed_as_stored(tmp_path, monkeypatch, capsys):
    folder = tmp_path / "s"
    record(ListSource(itertools.islice(endless_packets(True), 40)), folder)  # 20 frames
    _disk_filling_after(monkeypatch, 5)
    assert main(["bins", str(folder), "--bins", "6"]) == 1
    err = capsys.readouterr().err
    assert "bins for b=6 not stored" in err and "MB free" in err and len(err.splitlines()) == 1
    monkeypatch.undo()
    with Session.open(folder) as session:
        assert 6 not in session.stored_bins() and session.has_bins(4)
    with pytest.raises(SessionError, match="free"):
        _disk_filling_after(monkeypatch, 0)
        with Session.open(folder) as session:
            session.bins(6)


RECORD_FOREVER = Path(__file__).with_name("record_forever.py")


def test_a_real_small_disk_through_the_recorder(tmp_path):
    mount = tmp_path / "small"
    mount.mkdir()
    size_mb = 2 * writer_module.MIN_FREE_BYTES // 2**20 + 8  # the reserve, the margin, data
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size_mb}m", "tmpfs", str(mount)],
        capture_output=True,
        check=False,
    )
    if mounted.returncode != 0:
        pytest.skip("no tmpfs can be mounted here (needs root); the injected tests cover it")
    try:
        done = subprocess.run(
            [sys.executable, str(RECORD_FOREVER), str(mount / "s")],
            capture_output=True,
            text=True,
            timeout=300,
            check=False,
        )
        assert done.returncode == 1, done.stderr
        assert "is full" in done.stderr.splitlines()[-1]
        with Session.open(mount / "s") as session:
            assert session.manifest.status == "interrupted" and session.frame_count > 0
            assert session.event_count == session.manifest.event_count
    finally:
        subprocess.run(["umount", str(mount)], check=False)


TINY_FIT = Path(__file__).parents[1] / "seenerf" / "tiny_fit.py"


def _fit_into(folder: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(TINY_FIT), str(folder)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def test_a_real_small_disk_under_a_fit(tmp_path):
    """A fit whose disk fills after its checkpoint, in its plots and renders: one line, exit 1."""
    alone = _fit_into(tmp_path / "roomy")
    assert alone.returncode == 0, alone.stderr
    checkpoint = (tmp_path / "roomy" / "fit" / "fast-full" / "checkpoint.pt").stat().st_size
    small = tmp_path / "small"
    (small / "fit").mkdir(parents=True)
    size_kb = checkpoint // 1024 + 24  # the checkpoint, the log and config, not the figures
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size_kb}k", "tmpfs", str(small / "fit")],
        capture_output=True,
        check=False,
    )
    if mounted.returncode != 0:
        pytest.skip("no tmpfs can be mounted here (needs root); the injected tests cover it")
    try:
        done = _fit_into(small)
        kept = (small / "fit" / "fast-full" / "checkpoint.pt").stat().st_size
    finally:
        subprocess.run(["umount", str(small / "fit")], check=False)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 1 and len(lines) == 1, done.stderr
    assert "Traceback" not in done.stderr
    assert "not written" in lines[0] and "MB free" in lines[0]
    assert "run the command again" in lines[0]
    assert kept == checkpoint  # the trained steps are kept: running again resumes and renders


def test_sigterm_while_adding_bins_is_one_line_and_stores_nothing_partial(
    tmp_path, monkeypatch, capsys
):
    import os
    import signal

    folder = tmp_path / "s"
    record(ListSource(itertools.islice(endless_packets(True), 40)), folder)  # 20 frames
    checks, before = [], signal.getsignal(signal.SIGTERM)

    def terminated_at_the_fifth_frame(path):
        checks.append(path)
        if len(checks) == 5:
            os.kill(os.getpid(), signal.SIGTERM)
        return shutil.disk_usage(path)

    monkeypatch.setattr(writer_module.shutil, "disk_usage", terminated_at_the_fifth_frame)
    assert main(["bins", str(folder), "--bins", "6"]) == 143
    assert capsys.readouterr().err.strip() == "seecap: bins: terminated (SIGTERM)"
    assert signal.getsignal(signal.SIGTERM) == before  # put back
    monkeypatch.undo()
    with Session.open(folder) as session:
        assert 6 not in session.stored_bins() and session.has_bins(4)
        assert session.manifest.status == "complete"


def test_poses_a_full_disk_cut_short_are_not_listed_as_stored(tmp_path, monkeypatch):
    import errno

    import numpy as np

    import davis_io.session.store as store
    from davis_io.session import SessionPoses

    folder = tmp_path / "s"
    record(ListSource(itertools.islice(endless_packets(True), 40)), folder)  # 20 frames

    def full_after_the_first_dataset(group, poses):
        group["c2w"] = poses.c2w
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(store, "_write_pose_datasets", full_after_the_first_dataset)
    poses = SessionPoses(
        c2w=np.tile(np.eye(4), (20, 5, 1, 1)),
        registered=np.ones((20, 5), bool),
        intrinsics=np.array([100.0, 100.0, 32.0, 24.0]),
        distortion=np.zeros(0),
        bounds=np.array([0.5, 4.0]),
    )
    with Session.open(folder) as session, pytest.raises(OSError, match="No space"):
        session.write_poses(4, poses)
    with Session.open(folder) as session:
        assert session.poses(4) is None


@pytest.fixture
def small_disk(tmp_path):
    """A 48 MB tmpfs of its own (needs the right to mount: root in a container, as CI runs)."""
    mount = tmp_path / "small-disk"
    mount.mkdir()
    made = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=48m", "tmpfs", str(mount)], capture_output=True
    )
    if made.returncode != 0:
        pytest.skip(f"cannot mount a small file system here: {made.stderr.decode().strip()}")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=False)


def test_a_disk_another_process_fills_ends_the_recording_in_one_line(small_disk):
    session = small_disk / "s"
    recorder = subprocess.Popen(
        [sys.executable, str(Path(__file__).with_name("record_forever.py")), str(session)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    for line in recorder.stdout:
        if int(line.split()[1]) >= 3:
            break
    # Another program takes every byte left, fails with ENOSPC and stops, as programs do.
    filler = os.open(small_disk / "filler", os.O_CREAT | os.O_WRONLY, 0o600)
    try:
        for _ in itertools.count():
            os.write(filler, bytes(1 << 16))
    except OSError:
        pass
    finally:
        os.close(filler)
    _, err = recorder.communicate(timeout=120)
    assert recorder.returncode == 1, err  # not killed by a signal (139 was a segfault)
    assert "Segmentation" not in err and "is full" in err
    (small_disk / "filler").unlink()
    if "marked interrupted" not in err:  # the other program took the room to close in, too
        assert "could not be updated" in err and "--repair" in err
        repair_session(session)
    with Session.open(session) as opened:
        assert not opened.needs_repair and opened.manifest.status == "interrupted"
        assert opened.frame_count >= 3
    assert not (session / writer_module.RESERVE_NAME).exists()
