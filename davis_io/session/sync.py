"""Pairing frames with the events of their exposure while a stream is still arriving (no I/O)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from davis_io.errors import SessionError
from davis_io.types import EVENT_DTYPE, Frame, empty_events

__all__ = ["ClosedWindow", "ExposureSync"]

_MIN_RETENTION_US = 500_000
_QUIET_CLOSE_US = 1_000_000
"""A window also closes when other records (IMU, triggers) are this far past its end: a static
scene may send no event for a long time."""
_NO_TIME = np.iinfo(np.int64).min


@dataclass(frozen=True)
class ClosedWindow:
    """A frame whose exposure window is closed, with the events around it and its loss flag.

    ``events`` holds every event of the window (and possibly some outside it: binning cuts).
    """

    frame: Frame
    events: np.ndarray
    events_lost: bool


class ExposureSync:
    """Hold recent events and waiting frames; release each frame once its window is closed.

    Released frames carry the events of their window, ready for :func:`davis_io.bins.bin_exposure`.

    A frame's window ``[exposure start, exposure end]`` is closed once an event later than the
    exposure end has arrived: events come in time order, so none with ``t <= end`` can follow
    (``davis-protocol.md`` §3.7; events in the same microsecond as the end marker may come just
    after it, which is why an equal time does not close the window). When no event comes (a
    still scene), IMU samples or triggers a second past the end close it too. At the end of
    the stream every waiting frame is released; one whose window reaches past the last record
    of the stream is flagged as having lost events (its end was never recorded).

    Events are kept in memory back to the earliest waiting exposure start, and at least
    ``retention_us`` behind the newest event (twice the longest start-of-exposure to
    end-of-frame span seen, at least 0.5 s), because a frame is delivered only after its
    readout. A frame whose exposure started before the kept events is binned with
    ``fetch_events`` (the events already written), so its bins are never silently short.

    Losses: :meth:`note_loss` marks that events were lost between the newest event seen so far
    and the next one to arrive; frames whose window overlaps that gap are flagged.
    """

    def __init__(self, fetch_events: Callable[[int, int], np.ndarray] | None = None):
        self._fetch = fetch_events
        self._chunks: list[np.ndarray] = []
        self._waiting: list[Frame] = []
        self._losses: list[tuple[int, int]] = []
        self._open_loss_start: int | None = None
        self._span_us = 0
        self.latest_t_us = _NO_TIME
        self.stream_t_us = _NO_TIME
        """Newest time of any record (events, IMU samples, triggers), µs."""

    def add_events(self, events: np.ndarray) -> None:
        """Take the next events of the stream (sorted, not earlier than those seen before)."""
        if events.dtype != EVENT_DTYPE:
            raise SessionError(f"events have dtype {events.dtype}, expected {EVENT_DTYPE}")
        if len(events) == 0:
            return
        times = events["t"]
        if times[0] < self.latest_t_us or np.any(times[1:] < times[:-1]):
            raise SessionError(
                f"event times go back (newest so far {self.latest_t_us} µs, this packet "
                f"{int(times[0])}..{int(times[-1])} µs): a session needs one increasing clock; "
                "record again after the timestamp reset"
            )
        if self._open_loss_start is not None:
            self._losses.append((self._open_loss_start, int(events["t"][0])))
            self._open_loss_start = None
        self._chunks.append(events)
        self.latest_t_us = int(events["t"][-1])
        self.stream_t_us = max(self.stream_t_us, self.latest_t_us)

    def note_time(self, t_us: int) -> None:
        """Record that the stream reached ``t_us`` (an IMU sample or trigger time)."""
        self.stream_t_us = max(self.stream_t_us, int(t_us))

    def add_frame(self, frame: Frame) -> None:
        """Queue a frame until its exposure window is closed."""
        self._waiting.append(frame)
        self._span_us = max(self._span_us, frame.readout_end_us - frame.exposure_start_us)

    def note_loss(self) -> None:
        """Record that events were lost after the newest event seen so far."""
        if self._open_loss_start is None:
            self._open_loss_start = self.latest_t_us

    @property
    def waiting(self) -> int:
        """Frames waiting for their window to close."""
        return len(self._waiting)

    def settle(self, *, final: bool = False) -> list[ClosedWindow]:
        """Release every frame whose window is closed (all of them when ``final``)."""
        ready, still_open = [], []
        for frame in self._waiting:
            end = frame.exposure_end_us
            closed = end < self.latest_t_us or end + _QUIET_CLOSE_US < self.stream_t_us
            (ready if final or closed else still_open).append(frame)
        self._waiting = still_open
        settled = [self._settle_one(frame) for frame in ready]
        self._trim()
        return settled

    def _settle_one(self, frame: Frame) -> ClosedWindow:
        start, end = frame.exposure_start_us, frame.exposure_end_us
        kept_from = int(self._chunks[0]["t"][0]) if self._chunks else self.latest_t_us + 1
        if start < kept_from and self._fetch is not None:
            window = self._fetch(start, end)
        else:
            window = self._window(start, end)
        uncovered = end >= self.stream_t_us  # the stream ended before this exposure did
        return ClosedWindow(frame, window, uncovered or self._lost_during(start, end))

    def _window(self, start_us: int, end_us: int) -> np.ndarray:
        """Concatenate the kept chunks that overlap ``[start_us, end_us]``."""
        parts = [c for c in self._chunks if c["t"][-1] >= start_us and c["t"][0] <= end_us]
        if not parts:
            return empty_events()
        # Joined as raw bytes: a plain copy, faster than joining structured records field by field.
        raw = [np.ascontiguousarray(part).view(np.uint8) for part in parts]
        return np.concatenate(raw).view(EVENT_DTYPE)

    def _lost_during(self, start_us: int, end_us: int) -> bool:
        """True when a known gap overlaps the window (an open gap runs to the future)."""
        gaps = list(self._losses)
        if self._open_loss_start is not None:
            gaps.append((self._open_loss_start, np.iinfo(np.int64).max))
        return any(gap_start <= end_us and gap_end >= start_us for gap_start, gap_end in gaps)

    def _trim(self) -> None:
        """Forget events and gaps older than every window that may still need them."""
        retention_us = max(_MIN_RETENTION_US, 2 * self._span_us)
        horizon = self.latest_t_us - retention_us
        if self._waiting:
            horizon = min(horizon, min(f.exposure_start_us for f in self._waiting))
        while self._chunks and int(self._chunks[0]["t"][-1]) < horizon:
            self._chunks.pop(0)
        self._losses = [gap for gap in self._losses if gap[1] >= horizon]
