"""Recording any packet source into a session folder that stays readable whatever stops it."""

from __future__ import annotations

import dataclasses
import errno
import queue
import shutil
import signal
import threading
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

from davis_io.errors import SessionError, describe_error
from davis_io.lens import read_camera_calibration
from davis_io.session.defaults import DEFAULT_BINS
from davis_io.session.folder import check_limits, check_preview, new_session_folder
from davis_io.session.layout import H5_NAME
from davis_io.session.manifest import (
    MANIFEST_NAME,
    STATUS_COMPLETE,
    STATUS_INTERRUPTED,
    SessionManifest,
    write_manifest,
)
from davis_io.session.preview import preview_image, write_preview
from davis_io.session.pump import Outcome, Progress, read_source, write_packets
from davis_io.session.status import RecordingStatus
from davis_io.session.sync import ExposureSync
from davis_io.session.unstated_exposure import UnstatedExposures
from davis_io.session.writer import MIN_FREE_BYTES, SessionWriter
from davis_io.types import PacketSource

__all__ = ["RecordingError", "RecordingResult", "record"]

_QUEUE_PACKETS = 256
_STATUS_INTERVAL_S = 0.5
_READER_JOIN_S = 5.0


@dataclass
class RecordingResult:
    """What a finished recording left behind.

    Attributes:
        folder: the session folder.
        manifest: the final manifest (status, counts, drops, measured exposure).
        warnings: every per-frame warning raised while recording.
    """

    folder: Path
    manifest: SessionManifest
    warnings: list[str] = field(default_factory=list)
    stop_signal: int = 0
    """The signal that stopped the recording (SIGINT, SIGTERM), 0 when none did."""

    @property
    def status(self) -> str:
        """``"complete"`` or ``"interrupted"``."""
        return self.manifest.status


class RecordingError(SessionError):
    """The recording stopped on an error; the session was closed and marked interrupted.

    Attributes:
        result: what was recorded up to the error.
    """

    def __init__(self, message: str, result: RecordingResult):
        super().__init__(message)
        self.result = result


def record(
    source: PacketSource,
    out_dir: Path | str,
    *,
    exposure_us: int | None = None,
    bins: int = DEFAULT_BINS,
    frames: int | None = None,
    duration_us: int | None = None,
    overwrite: bool = False,
    status_callback: Callable[[RecordingStatus], None] | None = None,
    preview: Path | str | None = None,
    drop_when_full: bool | None = None,
    queue_packets: int = _QUEUE_PACKETS,
    camera_calibration: Path | None = None,
    unstated_exposure_us: int | None = None,
) -> RecordingResult:
    """Record ``source`` into a new session folder.

    One thread reads the source, another writes ``session.h5`` through a bounded queue of
    ``queue_packets`` packets; the calling thread reports status and refreshes the preview.
    Ctrl-C stops the recording, keeps what was already read, and marks it interrupted.

    Args:
        source: any packet source (camera, AEDAT replay, emulator), not yet entered.
        out_dir: the session folder to create.
        exposure_us: exposure that was requested, µs (recorded for reference; None: not set).
        bins: event bins per exposure computed while recording.
        frames: stop after this many frames (None: no limit).
        duration_us: stop after this much device time, µs (None: no limit).
        overwrite: replace an existing session folder.
        status_callback: called about twice a second with a :class:`RecordingStatus`.
        preview: PNG refreshed with the newest frame and its events (checked every 0.5 s).
        drop_when_full: drop packets when the queue is full instead of waiting. None: drop only
            for a live camera (``source.info.origin == "usb"``), whose reader must never wait;
            replay and emulator sources wait, losing nothing.
        queue_packets: queue capacity in packets.
        camera_calibration: the camera's lens calibration file, stored in ``session.json``
            (read before anything is recorded: a file that cannot serve refuses the start).
        unstated_exposure_us: the exposure of frames whose source states none, µs (None:
            assumed from the frame interval; :mod:`davis_io.session.unstated_exposure`).

    Returns:
        The result; its manifest says ``complete`` or ``interrupted`` (Ctrl-C).

    Raises:
        UsageError: bad limits, or the folder exists and ``overwrite`` is False.
        SessionBusy: another process writes the session in ``out_dir`` (it is left as it is).
        RecordingError: the source or the disk failed; the session is closed, marked
            interrupted, and everything written before the failure is readable.
    """
    check_limits(bins, frames, duration_us)
    preview_path = check_preview(preview)
    started = datetime.now(UTC).isoformat(timespec="seconds")
    with new_session_folder(Path(out_dir), overwrite=overwrite) as folder, source:
        manifest = SessionManifest.from_source(
            source.info, b=bins, exposure_requested_us=exposure_us, start_time_utc=started
        )
        if camera_calibration is not None:
            lens = read_camera_calibration(camera_calibration, manifest.width, manifest.height)
            manifest = dataclasses.replace(manifest, lens=lens.to_json())
        run = _Run(source, folder, manifest, queue_packets, unstated_exposure_us)
        write_manifest(folder, manifest)
        if drop_when_full is None:
            drop_when_full = source.info.origin == "usb"
        with _signals_stop(run):
            run.start(drop_when_full=drop_when_full, frames=frames, duration_us=duration_us)
            run.supervise(status_callback, preview_path)
        return run.finish()


_STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_SIGNAL_NAMES = {signal.SIGINT: "Ctrl-C", signal.SIGTERM: "SIGTERM"}


@contextmanager
def _signals_stop(run: _Run):
    """While the threads run, Ctrl-C (SIGINT) and SIGTERM ask them to stop instead of raising.

    A KeyboardInterrupt can land between any two statements, also outside a ``try``; escaping
    while the writer thread still writes would close the HDF5 file under it. In the main thread
    the handler only sets flags, so the writer always finishes before the file is closed.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {
        number: signal.signal(number, lambda signum, _frame: run.interrupt(signum))
        for number in _STOP_SIGNALS
    }
    try:
        yield
    finally:
        for number, handler in previous.items():
            # None: the handler was not installed from Python; the default takes its place.
            signal.signal(number, signal.SIG_DFL if handler is None else handler)


class _Run:
    """One recording in progress: threads, queue, writer and the shared counters."""

    def __init__(
        self,
        source,
        folder: Path,
        manifest: SessionManifest,
        queue_packets: int,
        unstated_exposure_us: int | None,
    ):
        self.source, self.folder, self.manifest = source, folder, manifest
        self.packets: queue.Queue = queue.Queue(maxsize=queue_packets)
        self.stop = threading.Event()
        self.outcome = Outcome()
        self.progress = Progress(unstated=UnstatedExposures(unstated_exposure_us))
        self.stop_signal = 0
        self.writer = SessionWriter(
            folder / H5_NAME, width=manifest.width, height=manifest.height, b=manifest.b
        )
        self.sync = ExposureSync(self._written)
        self.threads: list[threading.Thread] = []
        self.warnings_seen: list[str] = []
        self.failure: Exception | None = None

    def _written(self, start_us: int, end_us: int):
        """Events already written (for a frame that arrived after they left memory)."""
        return self.writer.read_events(start_us, end_us)

    def start(self, *, drop_when_full: bool, frames: int | None, duration_us: int | None):
        reader = threading.Thread(
            target=read_source,
            args=(self.source, self.packets, self.stop, self.outcome, self.progress),
            kwargs={"drop_when_full": drop_when_full},
            name="seecap-reader",
            daemon=True,
        )
        writer = threading.Thread(
            target=write_packets,
            args=(self.packets, self.writer, self.sync, self.stop, self.outcome, self.progress),
            kwargs={
                "max_frames": frames,
                "duration_us": duration_us,
                "defer_when_busy": drop_when_full,
            },
            name="seecap-writer",
        )
        self.threads = [reader, writer]
        for thread in self.threads:
            thread.start()

    def supervise(self, status_callback, preview: Path | None) -> None:
        """Report status until the writer is done; Ctrl-C asks both threads to stop.

        A failing status callback or preview stops the recording (kept as ``self.failure``).
        """
        reader, writer = self.threads
        started = time.monotonic()
        last_status = (started, 0)
        last_preview = None
        while writer.is_alive():
            try:
                writer.join(timeout=_STATUS_INTERVAL_S)
                if self.failure is not None:
                    continue
                if status_callback is not None:
                    last_status = self._report(status_callback, started, last_status)
                if preview is not None and self.progress.preview is not last_preview:
                    last_preview = self._refresh_preview(preview)
            except Exception as error:  # the display failed: stop, keep what was recorded
                self.failure = error
                self.stop.set()
        reader.join(timeout=_READER_JOIN_S)

    def interrupt(self, signal_number: int) -> None:
        """Ctrl-C or SIGTERM: stop both threads; the session is kept and marked interrupted."""
        self.stop_signal = signal_number
        self.stop.set()

    def _report(self, callback, started: float, last: tuple[float, int]) -> tuple[float, int]:
        now, events = time.monotonic(), self.progress.events
        rate = (events - last[1]) / max(now - last[0], 1e-9)
        warnings = self.progress.take_warnings()
        self.warnings_seen.extend(warnings)
        size = (self.folder / H5_NAME).stat().st_size if (self.folder / H5_NAME).exists() else 0
        callback(
            RecordingStatus(
                elapsed_s=now - started,
                frames=self.progress.frames,
                events=events,
                events_per_s=rate,
                bytes_written=size,
                queue_fill=self.packets.qsize() / self.packets.maxsize,
                drops=self.progress.drops,
                exposure_measured_us=self.progress.exposure_measured_us,
                warnings=warnings,
            )
        )
        return now, events

    def _refresh_preview(self, path: Path):
        shown = self.progress.preview
        if shown is not None:
            write_preview(path, preview_image(*shown))
        return shown

    def finish(self) -> RecordingResult:
        """Close the file, write the final manifest, raise if an error stopped the recording."""
        close_error = _close_quietly(self.writer)
        outcome = self.outcome
        storage_error = outcome.storage_error or close_error
        manifest = self.manifest
        manifest.frame_count = self.writer.frames_written
        manifest.event_count = self.writer.events_written
        manifest.drops = self.progress.drops
        manifest.exposure_measured_us = self.progress.exposure_measured_us
        manifest.exposure_assumed_us = self.progress.unstated.median_us
        if manifest.exposure_assumed_us is not None:
            self.progress.warnings.append(self._assumed_exposure_warning())
        manifest.stop_time_utc = datetime.now(UTC).isoformat(timespec="seconds")
        manifest.source_notes = list(self.progress.source_notes)
        manifest.event_gaps_us = self.progress.event_gaps(self.writer.events_written).tolist()
        message = self._error_message(storage_error)
        reason = message or self._stop_reason()
        clean = not reason and (outcome.source_exhausted or outcome.limit_reached)
        manifest.status = STATUS_COMPLETE if clean else STATUS_INTERRUPTED
        manifest.stop_reason = reason or ("" if clean else "the source stopped early")
        self.warnings_seen.extend(self.progress.take_warnings())
        result = RecordingResult(
            self.folder, manifest, list(self.warnings_seen), stop_signal=self.stop_signal
        )
        try:
            write_manifest(self.folder, manifest)
        except OSError as error:
            message = (
                f"{message or 'the recording could not be closed'}. {self.folder / MANIFEST_NAME} "
                f"could not be updated ({error.strerror or error}): its "
                f"{self.writer.frames_written} frames and {self.writer.events_written} events are "
                f"readable; free some space, then `seecap inspect {self.folder} --repair` marks "
                "the session interrupted"
            )
        else:
            message = message and f"{message}. {self._kept()}"
        if message:
            raise RecordingError(message, result)
        return result

    def _kept(self) -> str:
        return (
            f"The session {self.folder} was closed and marked interrupted; its "
            f"{self.writer.frames_written} frames and {self.writer.events_written} events are "
            "readable."
        )

    def _assumed_exposure_warning(self) -> str:
        unstated = self.progress.unstated
        how = (
            "the exposure given with --exposure"
            if unstated.given_us is not None
            else "half the time to the next frame"
        )
        return (
            f"{len(unstated.assumed_us)} frames state no exposure (its start and end "
            f"alike): each was given one from its start, {how} (median "
            f"{unstated.median_us / 1000:.1f} ms), stored as assumed in session.json; record "
            "again with --exposure to give the real one"
        )

    def _stop_reason(self) -> str:
        """Why a recording that did not fail is incomplete ("" when it is not)."""
        if self.stop_signal:
            return f"interrupted ({_SIGNAL_NAMES.get(self.stop_signal, self.stop_signal)})"
        if self.progress.truncated_at is not None:
            latest = self.progress.latest_t_us
            kept = "no event before it" if latest is None else f"the events up to t={latest} µs"
            return (
                f"the source file is truncated at byte offset {self.progress.truncated_at}: "
                f"what followed is lost; kept {self.writer.frames_written} frames and {kept}"
            )
        return ""

    def _error_message(self, storage_error: OSError | None) -> str:
        """One sentence on what stopped the recording ("" when nothing failed)."""
        outcome = self.outcome
        if storage_error is not None:
            return _describe_storage_error(storage_error, self.folder)
        if outcome.write_error is not None:
            return f"could not store the data: {describe_error(outcome.write_error)}"
        if outcome.source_error is not None:
            error = outcome.source_error
            return f"the source failed: {type(error).__name__}: {error}"
        if self.failure is not None:
            error = self.failure
            return f"the status display failed: {type(error).__name__}: {error}"
        return ""


def _close_quietly(writer: SessionWriter) -> OSError | None:
    """Close the writer; return the OSError a full disk may raise instead of raising it."""
    try:
        writer.close()
    except OSError as error:
        return error
    return None


def _describe_storage_error(error: OSError, folder: Path) -> str:
    """Say whether the disk is full and how much room is left."""
    try:
        free_mb = shutil.disk_usage(folder).free / 1e6
    except OSError:
        free_mb = float("nan")
    full = (
        error.errno == errno.ENOSPC or "No space left" in str(error) or "errno = 28" in str(error)
    )
    if full:
        return (
            f"the disk holding {folder} is full ({free_mb:.0f} MB free; a recording stops with "
            f"{MIN_FREE_BYTES / 1e6:.0f} MB still free, so that its files close intact): free "
            "some space or record to another disk with --out"
        )
    return f"writing {folder / H5_NAME} failed ({error}); {free_mb:.0f} MB free"
