"""The writer thread's deferral: binning waits while the queue is busy, and catches up exactly."""

import queue
import threading

import h5py
import numpy as np
from session_fakes import HEIGHT, WIDTH, synthetic_packets

from davis_io.bins import bin_exposure
from davis_io.session.pump import END_OF_STREAM, Outcome, Progress, write_packets
from davis_io.session.sync import ExposureSync
from davis_io.session.writer import SessionWriter


def test_deferred_frames_are_binned_later_from_the_stored_events(tmp_path, monkeypatch):
    read_back = []
    original = SessionWriter.read_events

    def counting(self, t0_us, t1_us):
        read_back.append(t0_us)
        return original(self, t0_us, t1_us)

    monkeypatch.setattr(SessionWriter, "read_events", counting)
    packets = synthetic_packets(8)
    items = [(packet, 0) for packet in packets]
    # A full queue at the start: the first frames close while it is more than half full.
    pending = queue.Queue(maxsize=len(items) + 1)
    for item in [*items, END_OF_STREAM]:
        pending.put(item)
    writer = SessionWriter(tmp_path / "session.h5", width=WIDTH, height=HEIGHT, b=3)
    outcome, progress = Outcome(), Progress()
    write_packets(
        pending,
        writer,
        ExposureSync(writer.read_events),
        threading.Event(),
        outcome,
        progress,
        max_frames=None,
        duration_us=None,
        defer_when_busy=True,
    )
    writer.close()
    assert outcome.storage_error is None and outcome.write_error is None
    # Frames closed while the queue was over half full were read back (deferred), not all.
    assert 0 < len(read_back) < 8
    events = np.concatenate([p.events for p in packets])
    with h5py.File(tmp_path / "session.h5", "r") as h5:
        starts = h5["frames/exposure_start_us"][()]
        np.testing.assert_array_equal(starts, np.arange(8) * 10_000 + 1_000)
        for index, start in enumerate(starts):
            direct = bin_exposure(events, int(start), int(start) + 4_000, 3, WIDTH, HEIGHT)
            np.testing.assert_array_equal(h5["bins/b3/calibrated"][index], direct.calibrated)
            assert h5["bins/b3/event_count"][index] == direct.event_count > 0
