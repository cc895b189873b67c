"""A fit's plan reads the session's own counts: its events and frames, what it holds already."""

import itertools

from session_fakes import ListSource, endless_packets

from davis_io.prepare import estimate_preparation, preparation_seconds
from davis_io.session import Session
from davis_io.session.recorder import record


def test_the_estimate_reads_the_recordings_events_and_frames(tmp_path):
    folder = tmp_path / "s"
    record(ListSource(itertools.islice(endless_packets(True), 40)), folder)  # 20 frames
    with Session.open(folder) as session:
        events, frames = session.event_count, session.frame_count
    assert events > 0 and frames == 20
    estimate = estimate_preparation(folder, 4)
    assert estimate == preparation_seconds(events, 20, 5, calibrated=False, posed=False)
    assert estimate.calibration_s > 0 and estimate.poses_s > 0
