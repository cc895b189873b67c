"""Pairing frames with their exposure events while the stream arrives."""

import numpy as np
from session_fakes import frame_at

from davis_io.session.sync import ExposureSync
from davis_io.types import EVENT_DTYPE, Frame


def events_at(times):
    events = np.zeros(len(times), EVENT_DTYPE)
    events["t"] = times
    events["p"] = 1
    return events


def test_window_closes_only_after_a_later_event():
    sync = ExposureSync()
    sync.add_events(events_at([1_000, 3_000, 5_000]))  # 5000 == exposure end of frame 0
    sync.add_frame(frame_at(0))
    # An event in the same µs as the end may still be followed by more at that µs: wait.
    assert sync.settle() == [] and sync.waiting == 1
    sync.add_events(events_at([5_000, 5_001]))
    (closed,) = sync.settle()
    np.testing.assert_array_equal(closed.events["t"], [1_000, 3_000, 5_000, 5_000, 5_001])
    assert not closed.events_lost and sync.waiting == 0


def test_end_of_stream_releases_waiting_frames():
    sync = ExposureSync()
    sync.add_events(events_at([2_000]))
    sync.add_frame(frame_at(0))
    assert sync.settle() == []
    (closed,) = sync.settle(final=True)
    assert closed.frame.exposure_start_us == 1_000
    assert closed.events_lost  # the stream ended (t=2000) before the exposure did (t=5000)


def test_frame_older_than_kept_events_is_read_back():
    calls = []

    def fetch(start_us, end_us):
        calls.append((start_us, end_us))
        return events_at([start_us, end_us])

    sync = ExposureSync(fetch)
    for start in range(0, 2_000_000, 100_000):  # 2 s of events, 100 ms per packet
        sync.add_events(events_at(np.arange(start, start + 100_000, 1_000)))
        sync.settle()
    # Kept: at least the last 0.5 s; a frame exposed at 1..5 ms arrives only now.
    late = Frame(np.zeros((6, 8), np.uint16), 1_000, 5_000, 0, 8_000)
    sync.add_frame(late)
    (closed,) = sync.settle()
    assert calls == [(1_000, 5_000)]
    np.testing.assert_array_equal(closed.events["t"], [1_000, 5_000])


def test_loss_flags_overlapping_windows_only():
    sync = ExposureSync()
    sync.add_events(events_at([500]))
    sync.note_loss()  # lost between t=500 and the next event (t=12 000)
    sync.add_events(events_at([12_000, 16_000, 26_000]))
    sync.add_frame(frame_at(0))  # window [1000, 5000]: inside the gap
    sync.add_frame(frame_at(1))  # window [11000, 15000]: overlaps the gap's end (12 000)
    sync.add_frame(frame_at(2))  # window [21000, 25000]: after it
    flags = [closed.events_lost for closed in sync.settle()]
    assert flags == [True, True, False]


def test_time_going_back_is_an_error():
    import pytest

    from davis_io.errors import SessionError

    sync = ExposureSync()
    sync.add_events(events_at([100, 200]))
    with pytest.raises(SessionError, match="event times go back"):
        sync.add_events(events_at([150]))
    with pytest.raises(SessionError, match="event times go back"):
        sync.add_events(events_at([300, 250]))


def test_a_still_scene_closes_windows_by_imu_time():
    sync = ExposureSync()
    sync.add_events(events_at([1_500]))
    sync.add_frame(frame_at(0))  # window [1000, 5000], no event after it
    sync.note_time(900_000)
    assert sync.settle() == []
    sync.note_time(1_005_001)  # more than a second past the end of the exposure
    (closed,) = sync.settle()
    assert not closed.events_lost
    np.testing.assert_array_equal(closed.events["t"], [1_500])
