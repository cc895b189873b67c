"""Pixel trains: interleaved events regrouped by pixel, against hand-made streams."""

import numpy as np

from davis_io.pixel_trains import pixel_trains

# Four pixels, events in camera (time) order: pixel 2 fires at 10, 40 and 45 µs; pixel 0 at 20
# and 30; pixel 3 at 25; pixel 1 never.
PIXEL = np.array([2, 0, 3, 0, 2, 2])
TIME_US = np.array([10, 20, 25, 30, 40, 45])


def test_events_are_grouped_by_pixel_in_time_order():
    trains = pixel_trains(PIXEL, TIME_US, 4)
    assert trains.pixel.tolist() == [0, 0, 2, 2, 2, 3]
    assert trains.time_us.tolist() == [20, 30, 10, 40, 45, 25]
    assert trains.order.tolist() == [1, 3, 0, 4, 5, 2]
    # Within a pixel only: 30-20, 40-10, 45-40 (never across pixels, e.g. 25-45).
    assert sorted(trains.intervals().tolist()) == [5, 10, 30]


def test_neighbours_of_a_time_point():
    trains = pixel_trains(PIXEL, TIME_US, 4)
    near = trains.around(30.0)
    # Pixel 0: its event at 30 counts as at or before; none after.
    assert near.has_before.tolist() == [True, False, True, True]
    assert near.has_after.tolist() == [False, False, True, False]
    assert trains.time_us[near.before[0]] == 30
    # Pixel 2: 10 before, 40 after.
    assert trains.time_us[near.before[2]] == 10 and trains.time_us[near.after[2]] == 40
    # Before every event nothing is before; after every event nothing is after.
    assert not trains.around(9.0).has_before.any()
    assert not trains.around(45.0).has_after.any()


def test_ticks_set_the_time_resolution():
    times = np.array([10.0, 10.5])
    fine = pixel_trains(np.zeros(2, np.int64), times, 1, tick_us=0.5).around(10.0)
    assert fine.has_before[0] and fine.has_after[0] and fine.after[0] == 1
    # At whole-microsecond ticks 10.4 rounds onto 10: at or before the point, not after it.
    coarse = pixel_trains(np.zeros(2, np.int64), np.array([10.0, 10.4]), 1).around(10.0)
    assert coarse.has_before[0] and not coarse.has_after[0]


def test_no_events():
    near = pixel_trains(np.zeros(0, np.int64), np.zeros(0, np.int64), 3).around(5.0)
    assert not near.has_before.any() and not near.has_after.any()
