"""Timestamp glitches: events whose time goes back or jumps ahead are dropped, the rest kept.

A real DAVIS stream (or a file with a damaged byte) now and then carries an event whose time
is wrong: far in the future, or behind the events before it. Refusing the whole recording for
it loses everything; keeping it breaks the one increasing clock a session needs. The events
kept are the longest run of the stream in time order (the longest non-decreasing subsequence
of its times), so an isolated glitch costs its own event only: one far ahead is dropped rather
than every event after it. When the last few events of a packet jump far ahead of the rest,
they are held until the next packet shows whether they were a glitch or the stream moved on.

A stream can also be out of order by a little everywhere: a file written by a converter or an
emulator that stamps each pixel's events on its own, a few microseconds either way. Its longest
ordered run is a small share of it (8 % of a stream jittered by 50 µs at 7.8 M events/s).
An event the run leaves out that lies within :data:`REORDER_US` of the run's events around it
is not a glitch but late or early by a little: it is kept, and the events are put in time order.
Once a stream has shown this, the last :data:`REORDER_US` of each packet waits for the next
one, whose first events may belong before them.
"""

from __future__ import annotations

from bisect import bisect_right

import numpy as np

from davis_io.types import EVENT_DTYPE, empty_events

__all__ = ["EventOrder", "longest_ordered"]

HELD_EVENTS = 64
"""How far from a packet's end a jump ahead makes the events after it wait for the next packet:
a glitch there can only be told from the events that follow it."""

JUMP_US = 1_000
"""A step between two events counts as a jump ahead when longer than this and than
:data:`JUMP_FACTOR` times the packet's median step."""

JUMP_FACTOR = 100

REORDER_US = 1_000
"""How far an event may stray from the events around it in the stream and still be put in time
order rather than dropped as a glitch."""


def longest_ordered(times: np.ndarray, floor: int) -> np.ndarray:
    """Mask of the longest non-decreasing run of ``times`` (a subsequence) at ``floor`` or later.

    Args:
        times: ``(N,)`` int64 event times, µs.
        floor: no kept time may be earlier (the newest time already accepted).

    Returns:
        ``(N,)`` bool, True for the events kept. An ordered input is kept whole without a search.
    """
    times = np.asarray(times, dtype=np.int64)
    if len(times) == 0 or (times[0] >= floor and np.all(times[1:] >= times[:-1])):
        return np.ones(len(times), dtype=bool)
    candidates = np.flatnonzero(times >= floor)
    # Patience sorting: tails[k] is the smallest last time of a kept run of length k + 1.
    tails: list[int] = []
    tail_index: list[int] = []
    previous = np.full(len(times), -1, dtype=np.int64)
    for index in candidates.tolist():
        value = int(times[index])
        length = bisect_right(tails, value)
        previous[index] = tail_index[length - 1] if length else -1
        if length == len(tails):
            tails.append(value)
            tail_index.append(index)
        else:
            tails[length], tail_index[length] = value, index
    keep = np.zeros(len(times), dtype=bool)
    index = tail_index[-1] if tail_index else -1
    while index >= 0:
        keep[index] = True
        index = int(previous[index])
    return keep


class EventOrder:
    """Pass a stream's event packets on in time order, dropping the glitched events.

    Attributes:
        dropped: events dropped so far.
        first_dropped_t_us: the time stamped on the first dropped event (None before one).
    """

    def __init__(self):
        self._held = empty_events()
        self._floor = np.iinfo(np.int64).min
        self.dropped = 0
        self.reordered = 0
        self.first_dropped_t_us: int | None = None

    def accept(self, events: np.ndarray) -> np.ndarray:
        """The events of this packet (and of those held) that are known to be in time order."""
        if len(events) == 0:
            return events
        joined = np.concatenate([self._held, events]) if len(self._held) else events
        kept = self._keep(joined)
        held_from = _jump_near_end(kept["t"])
        if self.reordered and len(kept):
            times = kept["t"]
            held_from = min(held_from, int(np.searchsorted(times, times[-1] - REORDER_US, "right")))
        self._held = kept[held_from:]
        return self._release(kept[:held_from])

    def finish(self) -> np.ndarray:
        """The events still held (at the end of the stream, or before a known loss)."""
        released, self._held = self._held, empty_events()
        return self._release(released)

    def _release(self, events: np.ndarray) -> np.ndarray:
        if len(events):
            self._floor = int(events["t"][-1])
        return events

    def note(self) -> str | None:
        """One line on what was reordered and dropped, for the session's source notes.

        None: the stream was in order.
        """
        said = []
        if self.reordered:
            said.append(
                f"put {self.reordered} events that came up to {REORDER_US} µs out of order back "
                "in time order"
            )
        if self.dropped:
            said.append(
                f"dropped {self.dropped} events whose time went back or jumped ahead of the "
                f"events around them (timestamp glitches; the first stamped "
                f"{self.first_dropped_t_us} µs)"
            )
        return "; ".join(said) or None

    def _keep(self, events: np.ndarray) -> np.ndarray:
        times = events["t"]
        keep = longest_ordered(times, self._floor)
        if keep.all():
            return events
        strays = _near_their_neighbours(times, keep) & (times >= self._floor)
        self.reordered += int(np.count_nonzero(strays))
        keep |= strays
        if not keep.all():
            if self.first_dropped_t_us is None:
                self.first_dropped_t_us = int(times[~keep][0])
            self.dropped += int(np.count_nonzero(~keep))
        kept = events[keep]
        return kept[np.argsort(kept["t"], kind="stable")].astype(EVENT_DTYPE, copy=False)


def _near_their_neighbours(times: np.ndarray, ordered: np.ndarray) -> np.ndarray:
    """Events outside the ordered run that lie within :data:`REORDER_US` of the run around them.

    Args:
        times: ``(N,)`` event times.
        ordered: ``(N,)`` bool, the events of the longest ordered run.

    Returns:
        ``(N,)`` bool, True for an event left out of the run whose time is no earlier than the
        run's event before it less :data:`REORDER_US` and no later than the run's event after
        it plus :data:`REORDER_US` (beyond the run's ends, its end event bounds both).
    """
    run = np.flatnonzero(ordered)
    strays = np.flatnonzero(~ordered)
    if len(run) == 0 or len(strays) == 0:
        return np.zeros(len(times), bool)
    after = np.searchsorted(run, strays)
    before_t = times[run[np.maximum(after - 1, 0)]]
    after_t = times[run[np.minimum(after, len(run) - 1)]]
    low = np.where(after > 0, before_t, after_t) - REORDER_US
    high = np.where(after < len(run), after_t, before_t) + REORDER_US
    near = np.zeros(len(times), bool)
    near[strays] = (times[strays] >= low) & (times[strays] <= high)
    return near


def _jump_near_end(times: np.ndarray) -> int:
    """Index of the first event after a jump ahead among the last :data:`HELD_EVENTS` (or len)."""
    if len(times) < 2:
        return len(times)
    steps = np.diff(times)
    tail = steps[-HELD_EVENTS:]
    limit = max(JUMP_US, JUMP_FACTOR * float(np.median(steps)))
    jumps = np.flatnonzero(tail > limit)
    if len(jumps) == 0:
        return len(times)
    return len(steps) - len(tail) + int(jumps[0]) + 1
