"""Gaps in an event stream: no event anywhere on the array for far longer than its rate allows.

A recording made view by view, or a USB stream that dropped out, has them. A DAVIS in any lit
scene fires thousands of events per second, its pixels' noise included, so a stretch of tens of
milliseconds without one event is not a still scene: what happened there was not recorded. A
pair of frames across such a gap has no events to tie them together, and an exposure that
overlaps one has lost its events.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "GAP_EVENTS",
    "MIN_GAP_US",
    "STILL_GYRO_DPS",
    "event_gaps",
    "find_gaps",
    "long_intervals",
    "not_still",
    "overlapping",
]

MIN_GAP_US = 20_000
"""No stretch shorter than this is a gap, whatever the rate."""

GAP_EVENTS = 1_000
"""A gap is at least as long as the stream takes, at its mean rate outside gaps, to fire this
many events: a chance lull of that length is practically impossible."""


STILL_GYRO_DPS = 1.0
"""A camera whose gyro reads less than this all through an event-free stretch was held still:
the stretch is a still scene, not lost data (a hand-held camera turns at several deg/s)."""


def long_intervals(times_us: np.ndarray, previous_us: int | None) -> np.ndarray:
    """``(K, 2)`` the event-free stretches of at least :data:`MIN_GAP_US` in ``times_us``.

    Args:
        times_us: ``(N,)`` sorted event times.
        previous_us: the time of the event before these (None: these are the first).
    """
    times = np.asarray(times_us, np.int64)
    if previous_us is not None:
        times = np.concatenate([[previous_us], times])
    if len(times) < 2:
        return np.zeros((0, 2), np.int64)
    steps = np.diff(times)
    index = np.flatnonzero(steps >= MIN_GAP_US)
    return np.stack([times[index], times[index + 1]], axis=1)


def event_gaps(candidates: np.ndarray, event_count: int, span_us: int) -> np.ndarray:
    """The candidate stretches ``(K, 2)`` that are gaps at the stream's rate outside them.

    Args:
        candidates: event-free stretches (:func:`long_intervals`).
        event_count: events in the whole stream.
        span_us: time from its first event to its last.
    """
    candidates = np.asarray(candidates, np.int64).reshape(-1, 2)
    if len(candidates) == 0 or event_count < 2:
        return np.zeros((0, 2), np.int64)
    lengths = candidates[:, 1] - candidates[:, 0]
    covered_us = max(span_us - int(lengths.sum()), 1)
    typical_us = GAP_EVENTS * covered_us / event_count
    return candidates[lengths >= max(MIN_GAP_US, typical_us)]


def find_gaps(times_us: np.ndarray, imu_t_us=None, gyro_dps=None) -> np.ndarray:
    """``(G, 2)`` start and end of every gap in a whole stream's sorted event times.

    With the IMU's times and gyro readings ``(M, 3)``, stretches it shows still are no gaps.
    """
    times = np.asarray(times_us, np.int64)
    if len(times) < 2:
        return np.zeros((0, 2), np.int64)
    gaps = event_gaps(long_intervals(times, None), len(times), int(times[-1] - times[0]))
    return gaps if imu_t_us is None else not_still(gaps, imu_t_us, gyro_dps)


def not_still(gaps: np.ndarray, imu_t_us: np.ndarray, gyro_dps: np.ndarray) -> np.ndarray:
    """The gaps without the parts in which the IMU shows the camera held still.

    A gap is cut down to the stretch between the first and the last gyro sample inside it
    that reads at least :data:`STILL_GYRO_DPS` (one sample period wider on each side); a gap
    with three or more samples inside, all still, is no gap. Without samples it stays whole.
    """
    gaps = np.asarray(gaps, np.int64).reshape(-1, 2)
    times = np.asarray(imu_t_us, np.int64)
    moving = np.linalg.norm(np.asarray(gyro_dps, np.float64).reshape(-1, 3), axis=1)
    moving = moving >= STILL_GYRO_DPS
    period = int(np.median(np.diff(times))) if len(times) > 1 else 0
    kept = []
    for start, end in gaps:
        inside = (times > start) & (times < end)
        if inside.sum() < 3:
            kept.append((start, end))
            continue
        turning = times[inside & moving]
        if len(turning):
            kept.append((max(start, turning[0] - period), min(end, turning[-1] + period)))
    return np.asarray(kept, np.int64).reshape(-1, 2)


def overlapping(gaps: np.ndarray, start_us: np.ndarray, end_us: np.ndarray) -> np.ndarray:
    """``(N,)`` True where ``[start_us, end_us]`` overlaps a gap's inside ``(gap start, end)``.

    A gap's ends are its last event before and first after: a window that only touches them
    lost nothing.
    """
    gaps = np.asarray(gaps, np.int64).reshape(-1, 2)
    start, end = np.asarray(start_us, np.int64), np.asarray(end_us, np.int64)
    if len(gaps) == 0:
        return np.zeros(start.shape, dtype=bool)
    # The last gap starting before the window ends is the only one that can reach into it.
    index = np.searchsorted(gaps[:, 0], end, side="left") - 1
    candidate = gaps[np.maximum(index, 0)]
    return (index >= 0) & (candidate[:, 1] > start)
