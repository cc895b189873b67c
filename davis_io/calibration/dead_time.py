"""``dead_time_us``: how soon a pixel fires again, measured from the event stream.

A DVS pixel that has just fired is blind for its refractory period; one that must fire many
times in a row (a bright edge sweeping across it) does so at most once per dead time, and the
rest of its change comes out later. Its events then follow each other at the dead time, so the
shortest intervals between consecutive events of one pixel pile up there; without a refractory
period they reach down to the sensor's timestamp resolution.
"""

from __future__ import annotations

import numpy as np

from davis_io.pixel_trains import pixel_trains

__all__ = ["DEAD_TIME_PERCENTILE", "dead_time_us"]

DEAD_TIME_PERCENTILE = 1.0
"""Percentile of a pixel's consecutive-event intervals taken as its dead time: a rate-limited
pixel contributes many intervals at the limit, so 1 % of them are at or under it."""

MAX_EVENTS = 20_000_000
"""Events the estimate reads at most (the first ones; the percentile is settled long before)."""


def dead_time_us(times_us: np.ndarray, x: np.ndarray, y: np.ndarray, width: int) -> int:
    """The :data:`DEAD_TIME_PERCENTILE` of the intervals between consecutive events of a pixel.

    Args:
        times_us: ``(N,)`` event times, µs, in order (as a camera sends them).
        x: ``(N,)`` event columns.
        y: ``(N,)`` event rows.
        width: sensor width (pixels are keyed ``y * width + x``).

    Returns:
        The interval in µs, 0 when fewer than two events share a pixel.
    """
    count = min(len(times_us), MAX_EVENTS)
    pixel = y[:count].astype(np.int64) * width + x[:count]
    intervals = pixel_trains(pixel, np.asarray(times_us[:count], np.int64)).intervals()
    if len(intervals) == 0:
        return 0
    return int(round(float(np.percentile(intervals, DEAD_TIME_PERCENTILE))))
