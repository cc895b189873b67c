"""The two recording threads: a reader that never waits on disk, a writer that bins and stores."""

from __future__ import annotations

import queue
import statistics
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from davis_io.bins import ExposureBins, bin_exposure
from davis_io.gaps import event_gaps, long_intervals, not_still
from davis_io.session.event_order import EventOrder
from davis_io.session.manifest import DropCounters
from davis_io.session.status import frame_warnings
from davis_io.session.sync import ClosedWindow, ExposureSync
from davis_io.session.unstated_exposure import UnstatedExposures
from davis_io.session.writer import SessionWriter
from davis_io.types import Packet, PacketSource, empty_events

__all__ = [
    "END_OF_STREAM",
    "MAX_SOURCE_NOTES",
    "Outcome",
    "Progress",
    "read_source",
    "write_packets",
]

MAX_SOURCE_NOTES = 100
END_OF_STREAM = object()
"""Queue item the reader puts last."""
_PUT_RETRY_S = 0.1
_FLUSH_INTERVAL_S = 0.5
_DEFER_ABOVE = 0.5
_CATCH_UP_BELOW = 0.1


@dataclass
class Progress:
    """Counters shared by the threads (each field has one writer thread; reads are snapshots)."""

    frames: int = 0
    events: int = 0
    first_t_us: int | None = None
    latest_t_us: int | None = None
    exposures_us: list[int] = field(default_factory=list)
    warnings: deque[str] = field(default_factory=deque)
    """Per-frame warnings not yet reported (appended by the writer, taken by the reporter)."""
    drops: DropCounters = field(default_factory=DropCounters)
    preview: tuple | None = None
    """(frame image, bit depth, net event counts) of the newest frame."""
    source_notes: list[str] = field(default_factory=list)
    """What the source said it skipped or lost (the first :data:`MAX_SOURCE_NOTES`)."""
    truncated_at: int | None = None
    """Byte offset at which the source's file ended inside a record (None: it did not)."""
    long_intervals: list[np.ndarray] = field(default_factory=list)
    """Event-free stretches long enough to be gaps (:func:`davis_io.gaps.long_intervals`)."""
    gyro: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)
    """The IMU's times and gyro readings, to tell a still camera from lost events."""
    unstated: UnstatedExposures = field(default_factory=UnstatedExposures)
    """Gives the frames that state no exposure an assumed one, and keeps what it assumed."""

    def event_gaps(self, event_count: int) -> np.ndarray:
        """The gaps of the stream so far (:func:`davis_io.gaps.event_gaps`, minus still ones)."""
        if self.first_t_us is None:
            return np.zeros((0, 2), np.int64)
        candidates = np.concatenate([np.zeros((0, 2), np.int64), *self.long_intervals])
        gaps = event_gaps(candidates, event_count, self.latest_t_us - self.first_t_us)
        times = np.concatenate([np.zeros(0, np.int64), *(t for t, _ in self.gyro)])
        gyro = np.concatenate([np.zeros((0, 3), np.float32), *(g for _, g in self.gyro)])
        return not_still(gaps, times, gyro)

    def take_warnings(self) -> list[str]:
        """Remove and return the warnings raised since the last call (thread-safe)."""
        taken = []
        while self.warnings:
            taken.append(self.warnings.popleft())
        return taken

    @property
    def exposure_measured_us(self) -> int | None:
        """Median exposure of the frames written, µs."""
        return int(statistics.median(self.exposures_us)) if self.exposures_us else None


@dataclass
class Outcome:
    """How the threads ended."""

    source_exhausted: bool = False
    limit_reached: bool = False
    source_error: BaseException | None = None
    storage_error: OSError | None = None
    write_error: Exception | None = None
    writer_done: threading.Event = field(default_factory=threading.Event)

    @property
    def writer_failed(self) -> bool:
        """True when storing failed (what the reader already queued cannot be written)."""
        return self.storage_error is not None or self.write_error is not None


def read_source(
    source: PacketSource,
    packets: queue.Queue,
    stop: threading.Event,
    outcome: Outcome,
    progress: Progress,
    *,
    drop_when_full: bool,
) -> None:
    """Reader thread: move packets from the source into the queue until stopped or exhausted.

    With ``drop_when_full`` a full queue drops the packet (counted in ``progress.drops``) instead
    of waiting, and the next queued packet carries the number of events dropped before it.
    """
    carried_loss = 0
    try:
        for packet in source:
            if stop.is_set():
                return
            if not drop_when_full:
                _put(packets, (packet, carried_loss), outcome)
                continue
            try:
                packets.put_nowait((packet, carried_loss))
                carried_loss = 0
            except queue.Full:
                carried_loss += len(packet.events)
                progress.drops.queue_packets += 1
                progress.drops.queue_events += len(packet.events)
                progress.drops.queue_frames += len(packet.frames)
        outcome.source_exhausted = not stop.is_set()
    except Exception as error:  # any source failure ends the recording cleanly
        outcome.source_error = error
        stop.set()
    finally:
        if carried_loss:
            _put(packets, (Packet(), carried_loss), outcome)  # losses after the last packet
        _put(packets, END_OF_STREAM, outcome)


def _put(packets: queue.Queue, item, outcome: Outcome) -> None:
    """Put ``item``, waiting for room, unless the writer has already finished."""
    while not outcome.writer_done.is_set():
        try:
            packets.put(item, timeout=_PUT_RETRY_S)
            return
        except queue.Full:
            continue


def write_packets(
    packets: queue.Queue,
    writer: SessionWriter,
    sync: ExposureSync,
    stop: threading.Event,
    outcome: Outcome,
    progress: Progress,
    *,
    max_frames: int | None,
    duration_us: int | None,
    defer_when_busy: bool = False,
) -> None:
    """Writer thread: store every packet, bin frames as their windows close, stop at the limits.

    With ``defer_when_busy`` (a live source whose packets are dropped when the queue is full),
    binning waits while the queue fills up, so that storing the stream keeps up. A frame that
    states no exposure is given one (``progress.unstated``).
    """
    state = _WriterState(writer, sync, progress, max_frames, duration_us)
    if defer_when_busy:
        state.backlog = lambda: packets.qsize() / max(packets.maxsize, 1)
    try:
        while (item := packets.get()) is not END_OF_STREAM:
            if outcome.writer_failed or outcome.limit_reached:
                continue  # drain so the reader never blocks
            try:
                outcome.limit_reached = state.consume(*item)
            except OSError as error:
                outcome.storage_error = error
            except Exception as error:  # noqa: BLE001 - any failure ends the recording, named
                outcome.write_error = error
            if outcome.writer_failed or outcome.limit_reached:
                stop.set()
        if not outcome.writer_failed:
            state.finish()
    except OSError as error:
        outcome.storage_error = error
    except Exception as error:  # noqa: BLE001 - any failure ends the recording, named
        outcome.write_error = error
    finally:
        state.close()
        outcome.writer_done.set()


class _WriterState:
    """What the writer thread keeps between packets.

    Closed exposure windows are binned on a helper thread while this one stores the next
    packets (HDF5 compression and most numpy work run without the GIL, so the two overlap);
    frames are stored in order as their bins come back. Storing the stream comes first: while
    the packet queue is more than half full, closed windows are not binned but deferred (only
    the frame is kept); they are binned from the stored events once the queue has drained to a
    tenth, or at the end of the recording.
    """

    def __init__(self, writer, sync, progress, max_frames, duration_us):
        self.writer, self.sync, self.progress = writer, sync, progress
        self.max_frames, self.duration_us = max_frames, duration_us
        self.frames_accepted = 0
        self.last_flush = time.monotonic()
        self.binner = ThreadPoolExecutor(max_workers=1, thread_name_prefix="seecap-binner")
        self.binning: deque[tuple[ClosedWindow, Future | None]] = deque()
        self.order = EventOrder()
        self.backlog: Callable[[], float] = lambda: 0.0
        """Fill of the packet queue, 0..1."""

    def consume(self, packet: Packet, queue_loss: int) -> bool:
        """Store one packet; return True once a frame or duration limit is reached."""
        if packet.dropped_events or queue_loss:
            self._add_events(self.order.finish())  # the loss comes after the events held
            self.sync.note_loss()
            self.progress.drops.source_events += packet.dropped_events
        self._note_source(packet)
        self._add_events(self.order.accept(packet.events))
        for records in (packet.imu, packet.triggers):
            if len(records):
                self.sync.note_time(records["t"].max())
        if len(packet.imu):
            self.progress.gyro.append((packet.imu["t"].copy(), packet.imu["gyro_dps"].copy()))
        self.writer.write_imu(packet.imu)
        self.writer.write_triggers(packet.triggers)
        unstated = self.progress.unstated
        for frame in packet.frames:
            within = self.max_frames is None or self.frames_accepted < self.max_frames
            for ready in (unstated.accept if within else unstated.released_by)(frame):
                self.sync.add_frame(ready)
            self.frames_accepted += within
        self._submit(self.sync.settle())
        self._store(wait=False)
        if time.monotonic() - self.last_flush > _FLUSH_INTERVAL_S:
            self.writer.flush()
            self.last_flush = time.monotonic()
        return self._limit_reached()

    def finish(self) -> None:
        """Store the last events and every waiting frame (flagged when its window was cut)."""
        self._add_events(self.order.finish())
        for ready in self.progress.unstated.finish():
            self.sync.add_frame(ready)
        note = self.order.note()
        if note is not None:
            self.progress.source_notes.append(note)
            self.progress.warnings.append(f"event times: {note} (stored in session.json)")
        self._submit(self.sync.settle(final=True))
        self._store(wait=True)
        self.writer.flush()

    def close(self) -> None:
        """Stop the binning thread (pending work is dropped)."""
        self.binner.shutdown(wait=True, cancel_futures=True)

    def _note_source(self, packet: Packet) -> None:
        progress = self.progress
        progress.source_notes.extend(packet.notes[: MAX_SOURCE_NOTES - len(progress.source_notes)])
        if packet.truncated_at is not None and progress.truncated_at is None:
            progress.truncated_at = packet.truncated_at

    def _add_events(self, events: np.ndarray) -> None:
        """Events in time order: to the exposure sync (which checks the order), then stored."""
        self.sync.add_events(events)
        self.writer.write_events(events)
        self.progress.events = self.writer.events_received
        if len(events):
            progress = self.progress
            intervals = long_intervals(events["t"], progress.latest_t_us)
            if len(intervals):
                progress.long_intervals.append(intervals)
            if progress.first_t_us is None:
                progress.first_t_us = int(events["t"][0])
            progress.latest_t_us = int(events["t"][-1])

    def _submit(self, closed: list[ClosedWindow]) -> None:
        for window in closed:
            if self.backlog() > _DEFER_ABOVE:
                deferred = ClosedWindow(window.frame, empty_events(), window.events_lost)
                self.binning.append((deferred, None))
            else:
                self.binning.append((window, self.binner.submit(self._bin, window)))

    def _bin(self, window: ClosedWindow, events: np.ndarray | None = None) -> ExposureBins:
        frame = window.frame
        return bin_exposure(
            window.events if events is None else events,
            frame.exposure_start_us,
            frame.exposure_end_us,
            self.writer.b,
            self.writer.width,
            self.writer.height,
        )

    def _ready_bins(self, *, wait: bool) -> list[tuple[ClosedWindow, ExposureBins]]:
        """Pop, in order, the frames whose bins are done (all of them when ``wait``).

        A deferred frame is binned here, from the stored events: one per call while the queue
        is nearly empty, every one of them when ``wait``.
        """
        done = []
        caught_up = 0
        while self.binning:
            window, future = self.binning[0]
            if future is None:  # deferred: bin from the stored events when there is time
                if not (wait or (caught_up == 0 and self.backlog() < _CATCH_UP_BELOW)):
                    break
                caught_up += 1
                frame = window.frame
                stored = self.writer.read_events(frame.exposure_start_us, frame.exposure_end_us)
                done.append((window, self._bin(window, stored)))
            elif wait or future.done():
                done.append((window, future.result()))
            else:
                break
            self.binning.popleft()
        return done

    def _store(self, *, wait: bool) -> None:
        """Write frames whose bins are ready, in order; flush; then count them."""
        done = self._ready_bins(wait=wait)
        if not done:
            return
        first_index = self.writer.frames_written
        for window, bins in done:
            self.writer.write_frame(window.frame, events_lost=window.events_lost, bins=bins)
        self.writer.flush()
        self.last_flush = time.monotonic()
        for index, (window, bins) in enumerate(done, start=first_index):
            self.progress.drops.frames_events_lost += int(window.events_lost)
            self.progress.exposures_us.append(window.frame.exposure_us)
            self.progress.warnings.extend(frame_warnings(index, window.frame, bins))
        newest, newest_bins = done[-1]
        net = newest_bins.raw.sum(axis=0, dtype=np.int32)
        self.progress.preview = (newest.frame.image, newest.frame.bit_depth, net)
        self.progress.frames = self.writer.frames_written

    def _limit_reached(self) -> bool:
        if self.max_frames is not None and self.writer.frames_written >= self.max_frames:
            return True
        first, latest = self.progress.first_t_us, self.progress.latest_t_us
        return (
            self.duration_us is not None
            and first is not None
            and latest - first >= self.duration_us
        )
