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
    "event_gaps",
    "find_gaps",
    "long_intervals",
    "overlapping",
]

MIN_GAP_US = 20_000
"""No stretch shorter than this is a gap, whatever the rate."""

GAP_EVENTS = 1_000
"""A gap is at least as long as the stream takes, at its mean rate outside gaps, to fire this
many events: a chance lull of that length is practically impossible."""


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


def find_gaps(times_us: np.ndarray) -> np.ndarray:
    """``(G, 2)`` start and end of every gap in a whole stream's sorted event times."""
    times = np.asarray(times_us, np.int64)
    if len(times) < 2:
        return np.zeros((0, 2), np.int64)
    return event_gaps(long_intervals(times, None), len(times), int(times[-1] - times[0]))


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
