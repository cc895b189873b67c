"""The one table of goals: each comparison at, above and below its limit, and unmeasured."""

import pytest
from benchlib.targets import BLIND_LOG_CONTRAST, Band, Target


@pytest.mark.parametrize(
    ("comparison", "below", "at", "above"),
    [
        (">=", False, True, True),
        ("<=", True, True, False),
        ("<", True, False, False),
        ("==", False, True, False),
    ],
)
def test_a_target_compares_its_figure_with_the_limit(comparison, below, at, above):
    target = Target(comparison, 2.0)
    assert (target.met(1.5), target.met(2.0), target.met(2.5)) == (below, at, above)


def test_an_unmeasured_figure_is_neither_met_nor_missed():
    assert Target(">=", 30.0).met(None) is None
    assert Band(0.8, 1.2).met(None) is None


def test_a_band_holds_both_of_its_ends():
    band = Band(0.8, 1.2)
    assert [band.met(v) for v in (0.79, 0.8, 1.0, 1.2, 1.21)] == [False, True, True, True, False]


def test_goals_read_as_the_reports_print_them():
    assert Target("<=", 120.0).goal == "<= 120"
    assert Target(">=", 0.5).goal == ">= 0.5"
    assert Target("<=", 3.0).in_words == "≤ 3"
    assert BLIND_LOG_CONTRAST.goal == "0.8-1.2"
