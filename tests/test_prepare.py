"""The preparation's progress lines, on a clock the test turns, and its estimated time."""

import pytest

from davis_io.prepare import StageLines, preparation_seconds


def test_stage_lines_say_each_stage_and_each_quarter_with_the_time_left():
    lines, now = [], [0.0]
    progress = StageLines(lines.append, clock=lambda: now[0])
    progress("features", 0, 0)
    for done in range(1, 9):
        now[0] = 2.0 * done  # two seconds per image
        progress("registering", done, 8)
    progress("matching", 0, 0)
    assert lines == [
        "poses: features",
        "poses: registering",
        "poses: registering 2/8 in 2 s, about 6 s left",
        "poses: registering 4/8 in 6 s, about 6 s left",
        "poses: registering 6/8 in 10 s, about 3 s left",
        "poses: registering 8/8 in 14 s, about 0 s left",
        "poses: matching",
    ]


def test_the_preparation_is_estimated_from_the_events_and_latent_frames():
    # 24 M events at 0.8 s a million; 80 latent frames: the neighbouring views' 976 pairs (120
    # keyframe pairs, 160 within views, 375 one view apart and 350 two apart, less the 29
    # keyframe pairs counted twice) at 0.012 s, 0.45 s each and 0.0015 s for each of the 6,400
    # squared.
    estimate = preparation_seconds(24_000_000, 16, 5, calibrated=False, posed=False)
    assert estimate.calibration_s == pytest.approx(19.2)
    assert estimate.poses_s == pytest.approx(11.712 + 36.0 + 9.6)
    assert estimate.total_s == pytest.approx(76.512)
    assert estimate.summary() == (
        "about 19 s to measure the sensor (24.0 M events) and 57 s for poses (80 latent frames)"
    )


def test_a_long_recordings_poses_are_estimated_from_the_pairs_it_matches():
    # 100 views x 5: not the 124,750 pairs of every latent frame but 10,678: 4,950 keyframe
    # pairs, 1,000 within views, 2,475 one view apart and 2,450 two apart, less the 197 keyframe
    # pairs counted twice; at 0.012 s a pair, 0.45 s for each of the 500 latent frames and
    # 0.0015 s for each of the 250,000 squared: 728 s, against 766 s measured.
    estimate = preparation_seconds(0, 100, 5, calibrated=True, posed=False)
    assert estimate.poses_s == pytest.approx(0.012 * 10_678 + 225.0 + 375.0)


def test_what_a_session_holds_already_takes_no_time():
    posed = preparation_seconds(24_000_000, 16, 5, calibrated=False, posed=True)
    assert (
        posed.poses_s == 0 and posed.summary() == "about 19 s to measure the sensor (24.0 M events)"
    )
    both = preparation_seconds(24_000_000, 16, 5, calibrated=True, posed=True)
    assert both.total_s == 0 and both.summary() == "the sensor and poses are stored"
