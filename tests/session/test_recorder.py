"""The recorder: limits, loss flags, queue overflow, source and disk failures, folder safety."""

import errno
import os
import signal
import time

import numpy as np
import pytest
from session_fakes import (
    ListSource,
    endless_packets,
    frame_at,
    random_events,
    synthetic_packets,
)

from davis_io.errors import DeviceError, UsageError
from davis_io.session import Session
from davis_io.session.folder import default_session_name
from davis_io.session.recorder import RecordingError, record
from davis_io.session.writer import SessionWriter
from davis_io.types import Packet


def test_frame_limit_stops_after_n_frames(tmp_path):
    source = ListSource(synthetic_packets(6))
    result = record(source, tmp_path / "s", frames=3)
    assert result.status == "complete" and result.manifest.frame_count == 3
    assert source.entered and source.exited
    with Session.open(tmp_path / "s") as session:
        assert session.frame_count == 3


def test_duration_limit_uses_device_time(tmp_path):
    # Events start near t=0; after 25 ms of device time the frames whose windows closed
    # (exposures ending at 5, 15, 25 ms need an event after their end) are the first two or three.
    result = record(ListSource(synthetic_packets(6)), tmp_path / "s", duration_us=25_000)
    assert result.status == "complete"
    assert 2 <= result.manifest.frame_count <= 3
    assert result.manifest.event_count <= 3 * 400


def test_events_lost_flags_only_the_overlapping_frame(tmp_path):
    rng = np.random.default_rng(1)
    packets = [
        Packet(events=random_events(rng, 0, 2_000, 50)),
        # Lost before t=2500..: the gap runs from 1999-ish to 2500, inside frame 0's [1000, 5000].
        Packet(events=random_events(rng, 2_500, 10_000, 50), dropped_events=7),
        Packet(frames=[frame_at(0)]),
        Packet(events=random_events(rng, 10_000, 20_000, 50)),
        Packet(frames=[frame_at(1)]),
        Packet(events=random_events(rng, 20_000, 20_001, 1)),
    ]
    result = record(ListSource(packets), tmp_path / "s")
    with Session.open(tmp_path / "s") as session:
        np.testing.assert_array_equal(session.frames_table().events_lost, [True, False])
    assert result.manifest.drops.source_events == 7
    assert result.manifest.drops.frames_events_lost == 1


def test_queue_overflow_is_counted_and_flagged(tmp_path, monkeypatch):
    original = SessionWriter.write_events

    def slow_write(self, events):
        time.sleep(0.05)
        original(self, events)

    monkeypatch.setattr(SessionWriter, "write_events", slow_write)
    rng = np.random.default_rng(2)
    burst = random_events(rng, 10_000, 20_000, 2_000)

    def paced():
        yield Packet(events=random_events(rng, 0, 10_000, 100))
        yield Packet(frames=[frame_at(0)])
        time.sleep(0.5)  # the writer empties the queue
        # Period 1 arrives in 20 packets at once: the 2-packet queue takes 2, the rest overflow.
        for chunk in np.array_split(burst, 20):
            yield Packet(events=chunk)
        time.sleep(0.5)
        yield Packet(frames=[frame_at(1)])
        yield Packet(events=random_events(rng, 20_000, 20_010, 5))

    result = record(ListSource(paced(), origin="usb"), tmp_path / "s", queue_packets=2)
    drops = result.manifest.drops
    assert drops.queue_packets >= 10
    # Every event is either stored or counted as dropped.
    assert result.manifest.event_count + drops.queue_events == 100 + 2_000 + 5
    with Session.open(tmp_path / "s") as session:
        # Frame 1's window [11 ms, 15 ms] lies in the dropped part of the burst; frame 0's not.
        np.testing.assert_array_equal(session.frames_table().events_lost, [False, True])
    assert drops.frames_events_lost == 1


def test_source_error_closes_the_session_interrupted(tmp_path):
    def failing():
        yield from synthetic_packets(3)
        raise DeviceError("camera unplugged")

    with pytest.raises(RecordingError, match="camera unplugged") as caught:
        record(ListSource(failing()), tmp_path / "s")
    assert caught.value.result.status == "interrupted"
    with Session.open(tmp_path / "s") as session:
        assert session.manifest.status == "interrupted"
        assert session.frame_count == 3 and not session.needs_repair


def test_full_disk_ends_with_a_clear_error_and_a_readable_session(tmp_path, monkeypatch):
    original = SessionWriter.write_events
    calls = {"n": 0}

    def fill_disk(self, events):
        calls["n"] += len(events) > 0
        if calls["n"] > 4:
            raise OSError(errno.ENOSPC, "No space left on device")
        original(self, events)

    def paced():
        for packet in synthetic_packets(10):
            time.sleep(0.05)  # lets each frame's bins come back before the next packet
            yield packet

    monkeypatch.setattr(SessionWriter, "write_events", fill_disk)
    with pytest.raises(RecordingError, match="disk holding .* is full") as caught:
        record(ListSource(paced()), tmp_path / "s")
    assert "marked interrupted" in str(caught.value)
    with Session.open(tmp_path / "s") as session:
        assert session.manifest.status == "interrupted"
        assert "full" in session.manifest.stop_reason
        # Packets: events 0, frame 0, events 1, frame 1, ... The 5th events write fails. Frame k
        # is binned when it arrives and stored while the next events packet is handled, so
        # frames 0..2 are stored and frame 3 is lost with the failing packet.
        assert session.frame_count == 3
        assert session.event_count == 4 * 400


def test_existing_session_is_never_overwritten_silently(tmp_path):
    record(ListSource(synthetic_packets(1)), tmp_path / "s")
    with pytest.raises(UsageError, match="--overwrite"):
        record(ListSource(synthetic_packets(2)), tmp_path / "s")
    result = record(ListSource(synthetic_packets(2)), tmp_path / "s", overwrite=True)
    assert result.manifest.frame_count == 2
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("keep me")
    with pytest.raises(UsageError, match="only replaces a session"):
        record(ListSource(synthetic_packets(1)), tmp_path / "other", overwrite=True)
    assert (tmp_path / "other" / "notes.txt").exists()


def test_no_frames_and_no_events(tmp_path):
    result = record(ListSource([]), tmp_path / "s")
    assert result.status == "complete"
    with Session.open(tmp_path / "s") as session:
        assert session.frame_count == 0 and session.event_count == 0
        assert len(session.events_between(0, 10**9)) == 0
        assert session.bins(6).raw.shape == (0, 6, 6, 8)


def test_status_callback_and_preview(tmp_path):
    seen = []

    def slow_packets():
        for packet in synthetic_packets(3):
            time.sleep(0.2)
            yield packet

    preview = tmp_path / "preview.png"
    record(ListSource(slow_packets()), tmp_path / "s", status_callback=seen.append, preview=preview)
    assert seen and seen[-1].frames >= 1
    assert preview.exists()
    import cv2

    image = cv2.imread(str(preview))
    assert image.shape == (6, 8 + 4 + 8, 3)


def test_default_session_name():
    from datetime import UTC, datetime

    assert default_session_name(datetime(2026, 3, 14, 15, 30, 9, tzinfo=UTC)) == (
        "session-20260314-153009"
    )


@pytest.mark.parametrize(
    ("kwargs", "message"), [({"bins": 0}, "--bins"), ({"frames": 0}, "--frames")]
)
def test_bad_limits(tmp_path, kwargs, message):
    with pytest.raises(UsageError, match=message):
        record(ListSource([]), tmp_path / "s", **kwargs)


def test_failing_status_display_stops_and_keeps_the_session(tmp_path):
    def broken(status):
        raise RuntimeError("terminal gone")

    def slow_packets():
        for packet in synthetic_packets(4):
            time.sleep(0.2)
            yield packet

    with pytest.raises(RecordingError, match="terminal gone"):
        record(ListSource(slow_packets()), tmp_path / "s", status_callback=broken)
    with Session.open(tmp_path / "s") as session:
        assert session.manifest.status == "interrupted" and not session.needs_repair


def test_preview_must_be_a_png_in_an_existing_folder(tmp_path):
    with pytest.raises(UsageError, match=".png"):
        record(ListSource([]), tmp_path / "s", preview=tmp_path / "p.jpg")
    with pytest.raises(UsageError, match="does not exist"):
        record(ListSource([]), tmp_path / "s", preview=tmp_path / "nowhere" / "p.png")


def test_events_whose_time_goes_back_are_dropped_and_noted(tmp_path):
    packets = synthetic_packets(3)
    backwards = packets[2].events.copy()
    backwards["t"] -= 50_000
    packets.insert(3, Packet(events=backwards))
    result = record(ListSource(packets), tmp_path / "s")
    assert result.status == "complete"
    with Session.open(tmp_path / "s") as session:
        times = session.events_between(-(2**62), 2**62)["t"]
        assert np.all(np.diff(times) >= 0)
        # The 400 events moved 50 ms back are dropped, every other one kept.
        assert session.event_count == 3 * 400 + 10
        assert "dropped 400 events" in session.manifest.source_notes[-1]


def test_ctrl_c_is_a_stop_request_while_the_threads_run(tmp_path):
    # A KeyboardInterrupt raised while the writer thread still writes would close the file
    # under it, so SIGINT only sets the stop flags for as long as the threads run.
    handlers, before = [], signal.getsignal(signal.SIGINT)  # SIG_IGN in a background job

    def press_ctrl_c(status):
        handlers.append(signal.getsignal(signal.SIGINT))
        os.kill(os.getpid(), signal.SIGINT)

    source = ListSource(endless_packets(with_frames=True))
    result = record(source, tmp_path / "s", status_callback=press_ctrl_c)
    assert result.status == "interrupted"
    assert result.manifest.stop_reason == "interrupted (Ctrl-C)"
    assert handlers and before not in handlers
    assert signal.getsignal(signal.SIGINT) is before  # restored
    with Session.open(tmp_path / "s") as session:
        assert not session.needs_repair and session.frame_count == result.manifest.frame_count
