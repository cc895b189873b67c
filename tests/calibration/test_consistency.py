"""The frame/event disagreement stays a number the threshold fit can compare."""

import math

import numpy as np

from davis_io.calibration.consistency import THRESHOLD_RANGE, ConsistencyProblem
from davis_io.calibration.pixel_events import PixelEvents


def _hot_pixel_problem() -> ConsistencyProblem:
    # Two frames, two pixels. Pixel 0 climbs 500 ON levels before its one piece in frame 1 (a
    # hot pixel): its blur term is e^(500 theta_on), which overflows above theta_on 1.42.
    events = PixelEvents(
        between_on=np.array([[500.0, 3.0]]),
        between_off=np.array([[0.0, 1.0]]),
        flat_share=np.array([[1.0, 1.0], [0.5, 1.0]]),
        piece_key=np.array([2], np.int64),  # frame 1, pixel 0
        piece_pixel=np.array([0], np.int32),
        piece_share=np.array([0.5], np.float32),
        piece_on=np.array([500.0], np.float32),
        piece_off=np.array([0.0], np.float32),
        rise_on=np.array([0.0], np.float32),
        rise_off=np.array([0.0], np.float32),
    )
    values = np.array([[0.3, 0.4], [0.5, 0.45]])
    return ConsistencyProblem(
        events,
        values,
        np.ones((1, 2), bool),
        np.linspace(0, 1, 16),
        np.ones(2),
        np.ones(2),
        np.zeros(2),
    )


def test_the_disagreement_is_finite_at_a_dvs_threshold():
    assert math.isfinite(_hot_pixel_problem().disagreement(0.3, 0.3))


def test_an_overflowing_blur_term_is_infinitely_bad_not_nan():
    # Unguarded it was NaN, and Nelder-Mead wandered on NaN to thresholds of 300.
    assert _hot_pixel_problem().disagreement(1.5, 0.3) == math.inf


def test_thresholds_outside_the_range_are_never_tried():
    problem = _hot_pixel_problem()
    low, high = THRESHOLD_RANGE
    for theta in ((high, 0.3), (0.3, high * 1.5), (low, 0.3), (0.3, low / 2)):
        assert problem.disagreement(*theta) == math.inf
