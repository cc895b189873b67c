"""Break-it: no run name, second writer or lock-file trick can delete or cut a recording."""

import errno
import hashlib
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from session_fakes import ListSource, synthetic_packets

from davis_io.errors import SessionError, UsageError
from davis_io.session import Session, SessionBusy, writer_lock
from davis_io.session.folder import empty_folder, plain_name
from davis_io.session.inspect import repair_session
from davis_io.session.lock import LOCK_NAME
from davis_io.session.recorder import record

RECORD_FOREVER = Path(__file__).with_name("record_forever.py")


def digest(folder: Path) -> dict[str, str]:
    """Every file under ``folder`` (the writer lock aside) and the SHA-256 of its bytes."""
    return {
        str(path.relative_to(folder)): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(folder.rglob("*"))
        if path.is_file() and path.name != LOCK_NAME
    }


@pytest.fixture
def session(tmp_path) -> Path:
    folder = tmp_path / "rec" / "session"
    record(ListSource(synthetic_packets(4)), folder)
    (folder / "fit" / "fast-full").mkdir(parents=True)
    (folder / "fit" / "fast-full" / "checkpoint.pt").write_bytes(b"weights")
    return folder


@pytest.fixture
def live_recording(tmp_path):
    """A recorder writing ``tmp_path/live`` in another process, until the test ends."""
    folder = tmp_path / "live"
    process = subprocess.Popen(
        [sys.executable, str(RECORD_FOREVER), str(folder)], stdout=subprocess.PIPE, text=True
    )
    try:
        for line in process.stdout:
            if int(line.split()[1]) >= 3:
                break
        yield folder, process
    finally:
        process.send_signal(signal.SIGINT)
        process.wait(timeout=60)


@pytest.mark.parametrize(
    "name", ["../..", "..", ".", "/abs", "a/b", "../x", "", ".hidden", "a\\b", "x" * 101, "a\0b"]
)
def test_a_run_name_is_one_plain_folder_name(name):
    with pytest.raises(UsageError, match="--run .* is not a plain name"):
        plain_name(name, "--run")


@pytest.mark.parametrize("name", ["fast-full", "run_2", "a.b+c", "x" * 100, "déjà-vu"])
def test_plain_names_pass(name):
    assert plain_name(name, "--run") == name


@pytest.mark.parametrize("run", ["../..", "..", "/abs", "../../x", "fit/../.."])
@pytest.mark.parametrize("fresh", [[], ["--fresh"]])
def test_fit_refuses_a_run_name_that_leaves_the_session_and_deletes_nothing(
    session, tmp_path, capsys, run, fresh
):
    from davis_io.cli import main

    outside = tmp_path / "rec" / "keep.txt"
    outside.write_text("not the session's")
    before, parent_before = digest(session), digest(tmp_path)
    run = str(tmp_path / "rec") if run == "/abs" else run
    assert main(["fit", str(session), "--run", run, *fresh, "--steps", "1"]) == 2
    err = capsys.readouterr().err
    assert "is not a plain name" in err and "Traceback" not in err
    assert digest(session) == before and digest(tmp_path) == parent_before
    assert not (session / "calibration").exists()


def test_fresh_empties_only_the_run_folder_never_through_a_link(session, tmp_path):
    from seenerf.errors import CheckpointError
    from seenerf.train.fit import start_over

    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "precious.txt").write_text("keep")
    (session / "fit" / "linked").symlink_to(elsewhere, target_is_directory=True)
    with pytest.raises(CheckpointError, match="symbolic link"):
        start_over(session / "fit" / "linked")
    assert (elsewhere / "precious.txt").read_text() == "keep"

    run = session / "fit" / "fast-full"
    (run / "renders").mkdir()
    (run / "renders" / "link").symlink_to(elsewhere, target_is_directory=True)
    before = digest(session)
    start_over(run)
    assert sorted(os.listdir(run)) == [LOCK_NAME]
    assert (elsewhere / "precious.txt").read_text() == "keep"
    assert {k: v for k, v in before.items() if not k.startswith("fit/")} == digest(session)


def test_render_out_is_a_name_inside_the_run(session):
    from seenerf.train.runs import render_run

    for name in ("../../x", "/tmp/x", ".."):
        with pytest.raises(UsageError, match="--out"):
            render_run(session / "fit" / "fast-full", (), None, name)


def test_overwrite_and_repair_of_a_live_recording_are_refused_with_its_pid(live_recording):
    from davis_io.cli import main

    folder, process = live_recording
    with pytest.raises(SessionBusy, match=f"process {process.pid} \\(recording"):
        record(ListSource(synthetic_packets(2)), folder, overwrite=True)
    with pytest.raises(SessionBusy, match=f"process {process.pid} \\(recording"):
        repair_session(folder)
    assert main(["inspect", str(folder), "--repair"]) == 1
    process.send_signal(signal.SIGINT)
    assert process.wait(timeout=60) == 0
    with Session.open(folder) as session:  # the recording went on to its end, whole
        assert session.manifest.status == "interrupted"
        assert session.frame_count == session.manifest.frame_count >= 3


@pytest.mark.parametrize("verb", ["calibrate", "poses", "fit"])
def test_no_other_writer_starts_on_a_live_recording(live_recording, capsys, verb):
    from davis_io.cli import main

    folder, process = live_recording
    assert main([verb, str(folder)]) == 1
    err = capsys.readouterr().err
    assert f"process {process.pid} (recording" in err and "Traceback" not in err


def test_the_lock_file_never_follows_a_link(tmp_path):
    target = tmp_path / "victim.txt"
    target.write_text("precious")
    folder = tmp_path / "s"
    folder.mkdir()
    (folder / LOCK_NAME).symlink_to(target)
    with pytest.raises(SessionError, match="symbolic link"):
        with writer_lock(folder, "fitting"):
            pass
    assert target.read_text() == "precious"


def test_a_lock_file_that_is_not_a_plain_file_is_refused(tmp_path):
    os.mkfifo(tmp_path / LOCK_NAME)  # a FIFO would block an open without O_NONBLOCK
    with pytest.raises(SessionError, match="not a plain file"):
        with writer_lock(tmp_path, "fitting"):
            pass


@pytest.mark.skipif(os.geteuid() != 0, reason="giving a file to another user needs root")
def test_a_folder_or_lock_of_another_user_is_refused(tmp_path):
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    os.chown(foreign, 65534, 65534)
    with pytest.raises(UsageError, match="belongs to another user"):
        record(ListSource(synthetic_packets(2)), foreign)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / LOCK_NAME).write_text("")
    os.chown(mine / LOCK_NAME, 65534, 65534)
    with pytest.raises(SessionError, match="not a plain file of this user's"):
        with writer_lock(mine, "fitting"):
            pass


class _FailingSource(ListSource):
    def __enter__(self):
        raise OSError(errno.ENODEV, "no such device")


def test_a_refused_start_leaves_no_session_behind(tmp_path, monkeypatch):
    folder = tmp_path / "new"
    with pytest.raises(OSError):
        record(_FailingSource([]), folder)
    assert not folder.exists()

    def full(folder, what, files_bytes=0):
        raise OSError(errno.ENOSPC, "1.0 MB free", str(folder))

    monkeypatch.setattr("davis_io.session.writer.check_free_space", full)
    with pytest.raises(SessionError, match="cannot create"):
        record(ListSource(synthetic_packets(2)), folder)
    assert not folder.exists()
    existing = tmp_path / "empty"
    existing.mkdir()
    with pytest.raises(SessionError):
        record(ListSource(synthetic_packets(2)), existing)
    assert sorted(os.listdir(existing)) == [LOCK_NAME]


def test_overwrite_refused_on_a_folder_without_a_session_deletes_nothing(tmp_path):
    folder = tmp_path / "photos"
    folder.mkdir()
    (folder / "a.jpg").write_bytes(b"jpeg")
    for overwrite in (False, True):
        with pytest.raises(UsageError):
            record(ListSource(synthetic_packets(2)), folder, overwrite=overwrite)
    assert (folder / "a.jpg").read_bytes() == b"jpeg"


def test_empty_folder_keeps_the_lock_and_removes_links_not_targets(tmp_path):
    target = tmp_path / "target"
    target.mkdir()
    (target / "f").write_text("x")
    folder = tmp_path / "f"
    (folder / "sub").mkdir(parents=True)
    (folder / "sub" / "g").write_text("y")
    (folder / LOCK_NAME).write_text("")
    (folder / "link").symlink_to(target, target_is_directory=True)
    empty_folder(folder)
    assert os.listdir(folder) == [LOCK_NAME] and (target / "f").read_text() == "x"


def test_a_failure_in_the_writer_thread_fails_the_recording(tmp_path, monkeypatch):
    from davis_io.cli import main
    from davis_io.session.recorder import RecordingError

    def broken(*args, **kwargs):
        raise ValueError("negative dimensions are not allowed")

    monkeypatch.setattr("davis_io.session.pump.bin_exposure", broken)
    with pytest.raises(RecordingError, match="could not store the data: ValueError: negative"):
        record(ListSource(synthetic_packets(3)), tmp_path / "s")
    with Session.open(tmp_path / "s") as session:
        assert session.manifest.status == "interrupted"
        assert "ValueError" in session.manifest.stop_reason
    # The CLI: exit 1 and its line, never 0.
    assert main(["record", "--emulate", "room", "--frames", "2", "--out", str(tmp_path / "t")]) == 1


def test_longest_ordered_by_hand():
    from davis_io.session.event_order import longest_ordered

    # 900 is a jump ahead, 5 went back: dropping those two keeps the rest in order.
    times = np.array([10, 20, 900, 30, 5, 40, 40, 50])
    assert longest_ordered(times, 0).tolist() == [1, 1, 0, 1, 0, 1, 1, 1]
    # Nothing may be earlier than the floor: the newest time already accepted.
    assert longest_ordered(np.array([10, 20, 30]), 15).tolist() == [0, 1, 1]
    assert longest_ordered(np.array([], dtype=np.int64), 0).tolist() == []


def test_a_glitch_at_a_packets_end_is_judged_by_the_next_packet():
    from davis_io.session.event_order import EventOrder
    from davis_io.types import EVENT_DTYPE

    def events(times):
        array = np.zeros(len(times), EVENT_DTYPE)
        array["t"] = times
        return array

    order = EventOrder()
    first = order.accept(events([*range(100, 300), 10**9]))  # the last one jumps ahead
    second = order.accept(events(range(300, 500)))
    kept = np.concatenate([first, second, order.finish()])["t"]
    assert first["t"].tolist() == list(range(100, 300))  # only the jump waited
    assert kept.tolist() == list(range(100, 500)) and order.dropped == 1
    assert "dropped 1 events" in order.note()
    # A stream that really moved on: the events after the jump are kept once confirmed.
    order = EventOrder()
    first = order.accept(events([*range(100, 300), 5_000_000]))
    second = order.accept(events(range(5_000_001, 5_000_200)))
    assert len(first) == 200 and len(second) == 200 and order.dropped == 0


def test_a_stream_out_of_order_by_a_little_everywhere_keeps_every_event_but_its_glitches():
    from davis_io.session.event_order import EventOrder
    from davis_io.types import EVENT_DTYPE

    rng = np.random.default_rng(3)
    count = 30_000
    events = np.zeros(count, EVENT_DTYPE)
    # 3 events per µs, each stamped up to 50 µs early or late; packets cut across the jitter.
    events["t"] = 1_000 + np.arange(count) // 3 + rng.integers(-50, 51, count)
    events["x"] = np.arange(count) % 346
    events["t"][12_000] = 10**9  # a glitch far ahead
    events["t"][25_000] = 7  # and one far back
    order = EventOrder()
    packets = np.split(events, [8_000, 16_000, 24_000])
    kept = np.concatenate([*(order.accept(packet) for packet in packets), order.finish()])
    assert np.all(np.diff(kept["t"]) >= 0)
    assert order.dropped == 2 and len(kept) == count - 2
    expected = np.delete(events, [12_000, 25_000])
    assert np.array_equal(np.sort(kept, order=["t", "x"]), np.sort(expected, order=["t", "x"]))
    assert order.reordered > count // 2
    assert "out of order back in time order" in order.note() and "dropped 2 events" in order.note()


def _aedat2_with_flipped_time_bytes(path, count, share, seed=1):
    """DVS events of a DAVIS346 as AEDAT 2.0 records; ``share`` of them get one time bit flipped."""
    header = (
        b"#!AER-DAT2.0\r\n# AEChip: eu.seebetter.ini.chips.davis.Davis346B\r\n"
        b"#End Of ASCII Header\r\n"
    )
    rng = np.random.default_rng(seed)
    times = np.sort(rng.integers(1_000, 2_001_000, count))
    x, y, p = rng.integers(0, 346, count), rng.integers(0, 260, count), rng.integers(0, 2, count)
    records = np.zeros(count, [("address", ">i4"), ("t", ">i4")])
    # davis-protocol.md §6.1: X field 345 - x at bit 12, Y field 259 - y at bit 22, ON bit 11.
    records["address"] = ((259 - y) << 22) | ((345 - x) << 12) | (p << 11)
    records["t"] = times
    raw = bytearray(records.tobytes())
    for index in rng.choice(count, int(count * share), replace=False):
        raw[8 * index + 4 + rng.integers(0, 4)] ^= 1 << rng.integers(0, 8)
    path.write_bytes(header + bytes(raw))


def test_one_percent_of_corrupted_times_keeps_98_percent_of_the_events(tmp_path):
    from davis_io.aedat import open_recording

    path = tmp_path / "glitches.aedat"
    _aedat2_with_flipped_time_bytes(path, 100_000, 0.01)
    result = record(open_recording(path), tmp_path / "s")
    assert result.status == "complete"
    with Session.open(tmp_path / "s") as session:
        times = session.events_between(0, 2**62)["t"]
        assert session.event_count >= 98_000 and np.all(np.diff(times) >= 0)
        assert 0 < 100_000 - session.event_count <= 1_000
        assert any("timestamp glitches" in note for note in session.manifest.source_notes)
    assert any("timestamp glitches" in warning for warning in result.warnings)


def test_a_writer_waits_for_a_reader_instead_of_losing_its_work(session):
    from davis_io.session import default_calibration

    reader = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time, h5py\n"
            "f = h5py.File(sys.argv[1], 'r')\n"
            "print('open', flush=True)\n"
            "time.sleep(2)\n",
            str(session / "session.h5"),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert reader.stdout.readline().strip() == "open"
    with Session.open(session) as opened:
        opened.write_calibration(default_calibration(0.25, "stated"))
    reader.wait(timeout=60)
    with Session.open(session) as opened:
        assert opened.calibration().threshold_on == 0.25
