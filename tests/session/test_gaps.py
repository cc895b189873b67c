"""Gaps in an event stream, by hand: how long, at which rate, and where the camera was still."""

import numpy as np

from davis_io.gaps import (
    GAP_EVENTS,
    MIN_GAP_US,
    event_gaps,
    find_gaps,
    long_intervals,
    not_still,
    overlapping,
)


def test_long_intervals_include_the_step_from_the_previous_packet():
    times = np.array([100, 200, 30_000, 30_100])
    assert long_intervals(times, None).tolist() == [[200, 30_000]]
    # The packet before ended at 50 - 25 000: its last event and this packet's first are 25 ms
    # apart, a candidate too.
    assert long_intervals(times, -25_000).tolist() == [[-25_000, 100], [200, 30_000]]


def test_a_gap_is_long_for_the_streams_own_rate():
    candidates = np.array([[0, 25_000], [100_000, 300_000]])
    # 10 000 events in 1 s outside the candidates (1.225 s span): 1000 events take 0.1 s, so
    # the 25 ms lull is chance and the 200 ms one a gap.
    assert event_gaps(candidates, 10_000, 1_225_000).tolist() == [[100_000, 300_000]]
    # At a million events per second both are gaps (MIN_GAP_US is the floor).
    assert event_gaps(candidates, 1_000_000, 1_225_000).tolist() == candidates.tolist()
    assert GAP_EVENTS == 1_000 and MIN_GAP_US == 20_000


def test_find_gaps_on_a_stream_recorded_view_by_view():
    rng = np.random.default_rng(0)
    windows = [(k * 200_000, k * 200_000 + 50_000) for k in range(5)]
    times = np.sort(np.concatenate([rng.integers(a, b, 5_000) for a, b in windows]))
    gaps = find_gaps(times)
    assert len(gaps) == 4
    assert all(149_000 < end - start < 151_000 for start, end in gaps)


def test_overlapping_windows_by_hand():
    gaps = np.array([[100, 200], [500, 600]])
    start = np.array([0, 150, 200, 450, 600, 700])
    end = np.array([100, 160, 300, 510, 650, 800])
    # Touching a gap's end events loses nothing; reaching inside does.
    assert overlapping(gaps, start, end).tolist() == [False, True, False, True, False, False]
    assert overlapping(np.zeros((0, 2)), start, end).tolist() == [False] * 6


def test_the_gyro_tells_a_still_camera_from_lost_events():
    imu_t = np.arange(0, 1_000_000, 1_000)
    gyro = np.zeros((len(imu_t), 3))
    gyro[imu_t >= 600_000, 0] = 20.0  # turning from 0.6 s on
    gaps = np.array([[100_000, 300_000], [500_000, 800_000], [900_000, 900_500]])
    # Still all through the first: no gap. The second is cut to where it turned. The third has
    # no sample inside: kept whole.
    assert not_still(gaps, imu_t, gyro).tolist() == [[599_000, 800_000], [900_000, 900_500]]
