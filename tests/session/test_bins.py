"""Equal-count bins, trapezoid weights and the h() calibration against hand-computed values."""

import numpy as np
import pytest

from davis_io.bins import BinningError, bin_exposure, split_times_us, subdivide, trapezoid_weights
from davis_io.types import EVENT_DTYPE


def events_of(rows):
    """Build an event array from (t, x, y, p) tuples."""
    return np.array(rows, dtype=EVENT_DTYPE)


def test_same_polarity_across_boundary_and_opposite_polarity():
    # 4 events, b = 2: event n goes to bin floor(2n/4) -> 0, 0, 1, 1; s_1 = t[2] = 40.
    events = events_of([(10, 0, 0, 1), (20, 1, 0, 1), (40, 0, 0, 1), (70, 1, 0, -1)])
    bins = bin_exposure(events, 0, 100, 2, width=2, height=1)
    np.testing.assert_array_equal(bins.split_us, [0, 40, 100])
    # T = [0, 0, 40, 100, 100]: w = [40/200, 100/200, 60/200].
    np.testing.assert_allclose(bins.weights, [0.2, 0.5, 0.3])
    np.testing.assert_array_equal(bins.raw[:, 0, :], [[1, 1], [1, -1]])
    # x=0: same polarity +1. gap_end = (40 - 10) + 1 = 31, gap_pre = (40 - 40) + 1 = 1,
    # h = 31/32 moves from bin 1 to bin 0; the last bin then gets +0.5 (p_last = +1).
    # x=1: +1 then -1, opposite: no boundary change; last bin gets -0.5 (p_last = -1).
    expected = [[1 + 31 / 32, 1.0], [1 - 31 / 32 + 0.5, -1.5]]
    np.testing.assert_allclose(bins.calibrated[:, 0, :], expected, rtol=1e-6)
    assert bins.event_count == 4
    assert bins.raw.dtype == np.int16 and bins.calibrated.dtype == np.float32


def test_first_and_last_event_of_a_bin_are_used():
    # 6 events, b = 2: bins 0,0,0,1,1,1; s_1 = t[3] = 50. Pixel x=0 has +1 then -1 in bin 0
    # (last is -1 at t=30) and -1 at t=60 in bin 1 (first), so the boundary uses -1 / -1.
    events = events_of(
        [(10, 0, 0, 1), (20, 1, 0, 1), (30, 0, 0, -1), (50, 1, 0, 1), (60, 0, 0, -1), (90, 1, 0, 1)]
    )
    bins = bin_exposure(events, 0, 100, 2, width=2, height=1)
    np.testing.assert_array_equal(bins.split_us, [0, 50, 100])
    # x=0: gap_end = 50 - 30 + 1 = 21, gap_pre = 60 - 50 + 1 = 11, h = 21/32, p = -1:
    # bin 0 = 0 - 21/32, bin 1 = -1 + 21/32 - 0.5 (last bin, p_last = -1).
    # x=1: last of bin 0 is +1 at t=20, first of bin 1 is +1 at t=50 (exactly on the boundary):
    # gap_end = 50 - 20 + 1 = 31, gap_pre = 0 + 1 = 1, h = 31/32; bin 1 last is +1 -> +0.5.
    expected = [[-21 / 32, 1 + 31 / 32], [-1 + 21 / 32 - 0.5, 2 - 31 / 32 + 0.5]]
    np.testing.assert_allclose(bins.calibrated[:, 0, :], expected, rtol=1e-6)


def test_empty_next_bin_and_single_event_pixels():
    # 3 events, b = 3: one per bin, s = [t1, t2] = [40, 70].
    # x=0 fires only in bin 0 -> bin 1 empty there: bin 0 gets +p/2 (one-event pixel, +1.5).
    # x=1 fires only in bin 1 (p=-1) -> bin 2 empty: bin 1 gets -0.5; bin 0 was empty: nothing.
    # x=2 fires only in the last bin (p=+1): +0.5.
    events = events_of([(10, 0, 0, 1), (40, 1, 0, -1), (70, 2, 0, 1)])
    bins = bin_exposure(events, 0, 90, 3, width=3, height=1)
    np.testing.assert_array_equal(bins.split_us, [0, 40, 70, 90])
    expected = [[1.5, 0, 0], [0, -1.5, 0], [0, 0, 1.5]]
    np.testing.assert_allclose(bins.calibrated[:, 0, :], expected)
    # T = [0, 0, 40, 70, 90, 90], 2T_exp = 180: w = [40, 70, 50, 20] / 180.
    np.testing.assert_allclose(bins.weights, np.array([40, 70, 50, 20]) / 180)


def test_equal_timestamps_on_a_boundary():
    # Two +1 events in the same µs, b = 2: bins 0 and 1, s_1 = 50 equal to both event times.
    # gap_end = 0 + 1, gap_pre = 0 + 1 -> h = 1/2. Bin 0: 1 + 0.5; bin 1: 1 - 0.5 + 0.5 (last).
    events = events_of([(50, 0, 0, 1), (50, 0, 0, 1)])
    bins = bin_exposure(events, 0, 100, 2, width=1, height=1)
    np.testing.assert_array_equal(bins.split_us, [0, 50, 100])
    np.testing.assert_allclose(bins.calibrated.ravel(), [1.5, 1.0])
    np.testing.assert_allclose(bins.weights, [0.25, 0.5, 0.25])


def test_fewer_events_than_bins():
    # N = 2, b = 4: bin of event n is floor(4n/2) -> 0, 2; bin k starts at event ceil(2k/4):
    # k=1 -> event 1 (t=30), k=2 -> event 1 (t=30), k=3 -> index 2 = N -> exposure end.
    events = events_of([(10, 0, 0, 1), (30, 0, 0, 1)])
    bins = bin_exposure(events, 0, 100, 4, width=1, height=1)
    np.testing.assert_array_equal(bins.split_us, [0, 30, 30, 100, 100])
    # Bin 1 empty -> bin 0 gets +0.5; bin 3 empty -> bin 2 gets +0.5; last bin has no event.
    np.testing.assert_allclose(bins.calibrated.ravel(), [1.5, 0, 1.5, 0])
    # T = [0, 0, 30, 30, 100, 100, 100], 2T_exp = 200.
    np.testing.assert_allclose(bins.weights, [0.15, 0.15, 0.35, 0.35, 0.0])


def test_frame_with_zero_events():
    events = events_of([(5, 0, 0, 1), (205, 0, 0, 1)])  # both outside [10, 110]
    bins = bin_exposure(events, 10, 110, 4, width=3, height=2)
    assert bins.event_count == 0
    # No event: time points evenly spaced, trapezoid weights 1/8, 1/4, 1/4, 1/4, 1/8.
    np.testing.assert_array_equal(bins.split_us, [10, 35, 60, 85, 110])
    np.testing.assert_allclose(bins.weights, [0.125, 0.25, 0.25, 0.25, 0.125])
    assert bins.raw.shape == (4, 2, 3) and not bins.raw.any()
    assert bins.calibrated.shape == (4, 2, 3) and not bins.calibrated.any()
    empty = bin_exposure(np.empty(0, EVENT_DTYPE), 10, 110, 4, width=3, height=2)
    np.testing.assert_array_equal(empty.split_us, bins.split_us)


def test_window_includes_both_ends():
    events = events_of([(9, 0, 0, 1), (10, 0, 0, 1), (110, 0, 0, -1), (111, 0, 0, 1)])
    bins = bin_exposure(events, 10, 110, 1, width=1, height=1)
    assert bins.event_count == 2
    np.testing.assert_array_equal(bins.raw.ravel(), [0])
    # b = 1: only the last-bin rule applies: +p_last/2 = -0.5.
    np.testing.assert_allclose(bins.calibrated.ravel(), [-0.5])


def reference_calibration(events, start, end, b, width, height):
    """Straight per-pixel reading of seenerf-reference.md §1.6, for comparison."""
    window = [e for e in events.tolist() if start <= e[0] <= end]
    n = len(window)
    splits = split_times_us(np.array([e[0] for e in window], np.int64), start, end, b)
    per_bin = [[[] for _ in range(width * height)] for _ in range(b)]
    for index, (t, x, y, p) in enumerate(window):
        per_bin[index * b // n][y * width + x].append((t, p))
    out = np.zeros((b, width * height))
    for k in range(b):
        for pixel, found in enumerate(per_bin[k]):
            out[k, pixel] += sum(p for _, p in found)
    for pixel in range(width * height):
        for i in range(b - 1):
            here, after = per_bin[i][pixel], per_bin[i + 1][pixel]
            if here and after and here[-1][1] == after[0][1]:
                gap_end = splits[i + 1] - here[-1][0] + 1
                gap_pre = after[0][0] - splits[i + 1] + 1
                h = gap_end / (gap_end + gap_pre)
                out[i, pixel] += here[-1][1] * h
                out[i + 1, pixel] -= here[-1][1] * h
            elif here and not after:
                out[i, pixel] += 0.5 * here[-1][1]
        if per_bin[b - 1][pixel]:
            out[b - 1, pixel] += 0.5 * per_bin[b - 1][pixel][-1][1]
    return out.reshape(b, height, width)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_matches_a_per_pixel_reading_of_the_rules(seed):
    rng = np.random.default_rng(seed)
    count, width, height = 400, 5, 4
    events = np.zeros(count, EVENT_DTYPE)
    events["t"] = np.sort(rng.integers(0, 300, count))  # many equal times
    events["x"] = rng.integers(0, width, count)
    events["y"] = rng.integers(0, height, count)
    events["p"] = rng.choice([-1, 1], count)
    b = int(rng.integers(1, 7))
    bins = bin_exposure(events, 20, 280, b, width, height)
    expected = reference_calibration(events, 20, 280, b, width, height)
    np.testing.assert_allclose(bins.calibrated, expected, rtol=1e-6, atol=1e-6)
    window = events[(events["t"] >= 20) & (events["t"] <= 280)]
    assert bins.event_count == len(window)
    # The pixel totals change only by the +-0.5 terms, i.e. by a multiple of 0.5.
    change = bins.calibrated.sum(axis=0) - bins.raw.sum(axis=0)
    np.testing.assert_allclose(change * 2, np.round(change * 2), atol=1e-5)
    assert abs(bins.weights.sum() - 1.0) < 1e-12


def test_trapezoid_weights_of_a_zero_length_window_are_equal():
    np.testing.assert_allclose(trapezoid_weights(np.array([7, 7, 7])), [1 / 3] * 3)


def test_raw_counts_saturate_at_int16():
    events = np.zeros(40_000, EVENT_DTYPE)
    events["t"] = np.arange(40_000)
    events["p"] = 1
    bins = bin_exposure(events, 0, 40_000, 1, width=1, height=1)
    assert bins.raw.ravel()[0] == 32767
    assert bins.calibrated.ravel()[0] == pytest.approx(40_000.5)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"b": 0}, "b=0"),
        ({"exposure_end_us": -5}, "before it starts"),
        ({"width": 1}, "sensor size"),
    ],
)
def test_bad_arguments_raise_binning_error(kwargs, message):
    events = events_of([(10, 1, 0, 1), (20, 0, 0, 1)])
    arguments = {"exposure_start_us": 0, "exposure_end_us": 100, "b": 2, "width": 2, "height": 1}
    arguments.update(kwargs)
    with pytest.raises(BinningError, match=message):
        bin_exposure(events, **arguments)


def test_unsorted_events_are_rejected():
    events = events_of([(20, 0, 0, 1), (10, 0, 0, 1)])
    with pytest.raises(BinningError, match="not sorted"):
        bin_exposure(events, 0, 100, 2, width=1, height=1)


def test_subdivide_adds_evenly_spaced_points_inside_each_interval():
    np.testing.assert_array_equal(subdivide(np.array([0, 10, 30]), 2), [0, 5, 10, 20, 30])
    np.testing.assert_array_equal(subdivide(np.array([0.0, 0.4, 1.0]), 1), [0.0, 0.4, 1.0])
    # A zero-length interval keeps its points together.
    np.testing.assert_array_equal(subdivide(np.array([0, 0, 3]), 3), [0, 0, 0, 0, 1, 2, 3])
