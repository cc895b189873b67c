"""The thresholds' common scale counts as measured only where the disagreement rises."""

import numpy as np
import pytest

from davis_io.calibration.scale import MEASURED_RISE, PINNED_RISE, SCALES, ScaleProfile


def _profile(rise_per_octave: float) -> ScaleProfile:
    return ScaleProfile(SCALES, rise_per_octave * np.log2(SCALES) ** 2)


def test_a_rise_of_five_percent_within_a_factor_of_root_two_pins_the_scale():
    # At x0.71 and x1.41 (half an octave) the rise is a quarter of the rise per octave.
    pinned = _profile(0.2)
    assert pinned.pinned
    assert pinned.interval() == pytest.approx((SCALES[3], SCALES[5]))


def test_a_flat_profile_leaves_the_scale_free_and_says_how_wide():
    free = _profile(0.02)  # +0.5 % at x1.41, +1.1 % at x1.68, +2 % at x2
    assert not free.pinned
    assert free.interval() == pytest.approx((SCALES[1], SCALES[7]))
    assert "x2.00: +2.0 %" in free.describe()


def test_scales_the_fit_may_not_try_bound_the_interval_and_leave_it_free():
    # A fit at the top of the threshold range: every larger scale is infinitely bad.
    rise = np.where(SCALES > 1, np.inf, 0.001)
    profile = ScaleProfile(SCALES, rise)
    assert profile.interval() == pytest.approx((SCALES[0], 1.0))
    assert not profile.pinned


def test_a_rise_between_the_measured_and_the_width_levels_pins_the_scale_widely():
    # x0.71 and x1.41 sit half an octave out: a rise of 1.8 % there (room-s22's weakest draw).
    profile = _profile(4 * 0.018)
    assert MEASURED_RISE < 0.018 < PINNED_RISE
    assert profile.pinned
    # Its width is read at the higher level: the scales within a factor of 1.41 either side.
    assert profile.interval() == pytest.approx((SCALES[2], SCALES[6]))


def test_a_rise_of_one_percent_at_root_two_leaves_the_scale_free():
    # 16 ms exposures rose 0.9-1.2 % there, at a minimum 2.2 times the true scale.
    assert not _profile(4 * 0.012).pinned


def test_a_profile_without_one_finite_disagreement_leaves_the_scale_free():
    # Frames of zero exposure: the disagreement is NaN at the fit, so every rise is too.
    profile = ScaleProfile(SCALES, np.full(len(SCALES), np.nan))
    assert profile.interval() == pytest.approx((SCALES[0], SCALES[-1]))
    assert not profile.pinned
