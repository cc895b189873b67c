"""Settled time points: where a pixel had fired all it owed, against hand-made event trains."""

import numpy as np

from davis_io.settled import settled_points
from davis_io.types import EVENT_DTYPE


def _events(rows):
    """``(t, x, y, p)`` rows sorted by time, as ``EVENT_DTYPE``."""
    events = np.zeros(len(rows), EVENT_DTYPE)
    for name, values in zip(("t", "x", "y", "p"), zip(*rows, strict=True), strict=True):
        events[name] = values
    return events[np.argsort(events["t"], kind="stable")]


# A 3x2 sensor. Pixel (0, 0) slews: one ON event every 2 ms (its dead time). Pixel (1, 0) fires
# twice 10 ms apart; pixel (2, 1) once; the others never.
SLEWING = [(t, 0, 0, 1) for t in (0, 2000, 4000, 6000)]
EVENTS = _events([*SLEWING, (1000, 1, 0, 0), (11_000, 1, 0, 0), (3000, 2, 1, 1)])


def test_a_point_between_events_a_dead_time_apart_is_not_settled():
    settled = settled_points(EVENTS, np.array([3000, 8000, -5, 6000]), 3, 2, 2000)
    assert settled.shape == (4, 2, 3)
    # 3000 µs lies between the slewing pixel's events at 2000 and 4000: 2 ms <= 2 x 2 ms.
    assert not settled[0, 0, 0]
    # 8000 µs is after its last event; -5 µs before its first: nothing owed there.
    assert settled[1, 0, 0] and settled[2, 0, 0]
    # At 6000 µs the event at 6000 is before the point (at or before), none follows.
    assert settled[3, 0, 0]
    # The other pixels' intervals (10 ms) are longer than 4 ms, or they fired at most once.
    assert settled[:, 0, 1:].all() and settled[:, 1, :].all()


def test_the_limit_is_two_dead_times():
    # Events 2000 µs apart straddle 3000 µs: settled under a dead time of 999 µs (limit 1998),
    # not under 1000 µs (limit 2000).
    assert settled_points(EVENTS, np.array([3000]), 3, 2, 999)[0, 0, 0]
    assert not settled_points(EVENTS, np.array([3000]), 3, 2, 1000)[0, 0, 0]


def test_without_a_dead_time_every_point_is_settled():
    assert settled_points(EVENTS, np.array([1, 3000, 5000]), 3, 2, 0).all()


def test_pixels_do_not_see_each_others_events():
    # Pixel (1, 0)'s events at 1000 and 11000 would straddle 3000 µs within 4 ms of pixel
    # (0, 0)'s; each pixel is read on its own, whatever their order in the key.
    near = _events([(2500, 1, 0, 1), (3500, 2, 0, 1), (2900, 0, 1, 0), (3100, 0, 1, 0)])
    settled = settled_points(near, np.array([3000]), 3, 2, 100)
    assert settled[0, 0, 1] and settled[0, 0, 2]  # one event each
    assert not settled[0, 1, 0]  # 200 µs apart <= 2 x 100 µs
