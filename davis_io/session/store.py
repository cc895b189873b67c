"""Reading a session folder: manifest, frames, events by time, bins (made on demand) and poses."""

from __future__ import annotations

import errno
import signal
import threading
import time
from pathlib import Path

import h5py
import numpy as np

from davis_io.bins import bin_exposure
from davis_io.errors import SessionError
from davis_io.gaps import find_gaps, overlapping
from davis_io.session.calibration import (
    SensorCalibration,
    read_calibration,
    write_calibration,
)
from davis_io.session.layout import (
    EVENT_FIELDS,
    FRAME_TIMES,
    H5_NAME,
    bins_path,
    complete_rows,
    create_bins_group,
    dataset_filters,
    poses_path,
    read_events_between,
    write_bins_row,
)
from davis_io.session.lock import refuse_if_written, writer_lock
from davis_io.session.manifest import (
    MANIFEST_NAME,
    STATUS_COMPLETE,
    SessionManifest,
    read_manifest,
)
from davis_io.session.records import FramesTable, SessionBins, SessionPoses
from davis_io.session.truth import TRUTH_DIR, Truth, load_truth
from davis_io.session.writer import check_free_space, storage_errors
from davis_io.types import (
    EVENT_DTYPE,
    IMU_DTYPE,
    TRIGGER_DTYPE,
    Closing,
    ColorFilter,
    Frame,
    empty_events,
)

__all__ = ["Session"]

_BINS_FIELDS = ("split_us", "weights", "raw", "calibrated", "event_count")
_FRAME_FIELDS = ("image", "events_lost", *FRAME_TIMES)


class Session(Closing):
    """A recorded session folder, read through ``session.json`` and ``session.h5``.

    Open with :meth:`open`; use as a context manager to close the HDF5 file. A session whose
    writer was killed is still readable (HDF5 SWMR mode); :attr:`needs_repair` is then True and
    writing into it (bins for another b, poses) needs ``seecap inspect --repair`` first.
    """

    def __init__(self, folder: Path, manifest: SessionManifest, h5: h5py.File, needs_repair: bool):
        self.folder = folder
        self.manifest = manifest
        self._h5 = h5
        self.needs_repair = needs_repair
        self._found_gaps: np.ndarray | None = None

    @classmethod
    def open(cls, path: Path | str) -> Session:
        """Open a session folder (or its ``session.h5`` / ``session.json``).

        Raises:
            SessionError: no manifest, no HDF5 file, or a file HDF5 cannot read.
        """
        folder = Path(path)
        if folder.is_file():
            folder = folder.parent
        manifest = read_manifest(folder)
        h5_path = folder / H5_NAME
        if not h5_path.exists():
            raise SessionError(f"{h5_path} not found: the session holds no recorded data")
        try:
            session = cls(folder, manifest, h5py.File(h5_path, "r"), needs_repair=False)
        except OSError as error:
            if "already open for write" not in str(error):
                refuse_if_written(folder)  # a writer mid-flush: name it, not the file's state
                raise SessionError(f"{h5_path}: HDF5 cannot read it ({error})") from error
        else:
            try:
                session._check_structure()
            except SessionError:
                session.close()
                raise
            return session
        # A writer that never closed the file: read it as a single-writer/multi-reader reader.
        try:
            return cls(folder, manifest, h5py.File(h5_path, "r", swmr=True), needs_repair=True)
        except OSError as error:
            refuse_if_written(folder)
            if "not already open for SWMR writing" in str(error):
                raise SessionError(
                    f"{h5_path}: a process adding bins or poses was killed with the file open; "
                    f"the recording is intact: clear the open flag with `h5clear -s {h5_path}` "
                    "(HDF5's hdf5-tools) and run the step again"
                ) from error
            raise SessionError(f"{h5_path}: HDF5 cannot read it ({error})") from error

    def close(self) -> None:
        """Close the HDF5 file."""
        self._h5.close()

    def _check_structure(self) -> None:
        """Refuse a closed ``session.h5`` that lacks a dataset or disagrees with its manifest.

        Raises:
            SessionError: the first thing wrong, by dataset path or manifest field.
        """
        damaged = "the file was changed or damaged after recording; restore it from a copy"
        for group, names in (("events", EVENT_FIELDS), ("frames", _FRAME_FIELDS)):
            for name in names:
                if name == "image" and self.manifest.frame_count == 0:
                    continue  # created with the first frame
                if f"{group}/{name}" not in self._h5:
                    raise SessionError(f"{self.h5_path}: /{group}/{name} is missing: {damaged}")
        if self.manifest.status != STATUS_COMPLETE:
            return  # an interrupted recording's counts are what its repair found
        for what, stored, stated in (
            ("frame_count", self.frame_count, self.manifest.frame_count),
            ("event_count", self.event_count, self.manifest.event_count),
        ):
            if stored != stated:
                raise SessionError(
                    f"{self.h5_path}: holds {stored} but {MANIFEST_NAME} field {what!r} says "
                    f"{stated}: {damaged}"
                )

    def check_coordinates(self, chunk: int = 1 << 22) -> None:
        """Read every event and refuse one outside the sensor (a damaged file).

        Raises:
            SessionError: names the first such event by index, time and coordinates.
        """
        events = self._h5["events"]
        for first in range(0, self.event_count, chunk):
            stop = min(first + chunk, self.event_count)
            outside = (events["x"][first:stop] >= self.width) | (
                events["y"][first:stop] >= self.height
            )
            if outside.any():
                at = first + int(np.argmax(outside))
                self._inside_sensor(self.events_by_index(at, at + 1), at)

    @property
    def h5_path(self) -> Path:
        """Path of ``session.h5``."""
        return self.folder / H5_NAME

    @property
    def width(self) -> int:
        """Sensor width in pixels."""
        return self.manifest.width

    @property
    def height(self) -> int:
        """Sensor height in pixels."""
        return self.manifest.height

    @property
    def color_filter(self) -> ColorFilter:
        """Colour filter pattern of the sensor."""
        return self.manifest.filter_pattern

    @property
    def truth_dir(self) -> Path | None:
        """The ``truth/`` folder of an emulated session, or None."""
        truth = self.folder / TRUTH_DIR
        return truth if truth.is_dir() else None

    def truth(self) -> Truth | None:
        """The ground truth of an emulated session, or None: for scoring and oracles only.

        Raises:
            SessionError: ``truth/`` exists but cannot be read.
        """
        return load_truth(self.truth_dir) if self.truth_dir is not None else None

    @property
    def frame_count(self) -> int:
        """Complete frames stored (every per-frame dataset and the record-time bins hold them)."""
        count = complete_rows(self._h5.get("frames"), _FRAME_FIELDS)
        record_bins = bins_path(self.manifest.b)
        if record_bins in self._h5:
            count = min(count, complete_rows(self._h5[record_bins], _BINS_FIELDS))
        return count

    @property
    def event_count(self) -> int:
        """Events stored."""
        return complete_rows(self._h5.get("events"), EVENT_FIELDS)

    def frame(self, index: int) -> Frame:
        """Frame ``index`` (negative counts from the end) with its four timestamps.

        Raises:
            SessionError: index out of range.
        """
        count = self.frame_count
        if not -count <= index < count:
            raise SessionError(f"frame {index} out of range: the session has {count} frames")
        index %= count
        frames = self._h5["frames"]
        times = {name: int(frames[name][index]) for name in FRAME_TIMES}
        bit_depth = int(frames["image"].attrs.get("bit_depth", 10))
        return Frame(image=frames["image"][index], bit_depth=bit_depth, **times)

    def frames_table(self) -> FramesTable:
        """Timestamps and loss flags of every complete frame."""
        count = self.frame_count
        if count == 0:
            empty = np.zeros(0, np.int64)
            return FramesTable(empty, empty, empty, empty, np.zeros(0, np.bool_))
        frames = self._h5["frames"]
        columns = {name: frames[name][:count] for name in (*FRAME_TIMES, "events_lost")}
        # An exposure that overlaps a gap in the stream lost its events, as a dropped packet's.
        columns["events_lost"] = columns["events_lost"] | overlapping(
            self.event_gaps(), columns["exposure_start_us"], columns["exposure_end_us"]
        )
        return FramesTable(**columns)

    def filters(self) -> dict[str, list[str]]:
        """Each HDF5 compression filter ``session.h5`` uses and its datasets (``none``: plain)."""
        return dataset_filters(self._h5)

    def event_gaps(self) -> np.ndarray:
        """``(G, 2)`` start and end of each gap in the event stream, µs (:mod:`davis_io.gaps`).

        As ``session.json`` states them; for a session recorded before they were, found from
        its events (once per open session).
        """
        if self.manifest.event_gaps_us is not None:
            return np.asarray(self.manifest.event_gaps_us, np.int64).reshape(-1, 2)
        if self._found_gaps is None:
            times = self._h5["events"]["t"][: self.event_count] if self.event_count else []
            imu = self.imu()
            self._found_gaps = find_gaps(np.asarray(times, np.int64), imu["t"], imu["gyro_dps"])
        return self._found_gaps

    def events_between(self, t0_us: int, t1_us: int) -> np.ndarray:
        """Events with ``t0_us <= t <= t1_us`` (both ends included), as ``EVENT_DTYPE``."""
        if self.event_count == 0:
            return empty_events()
        events = read_events_between(self._h5["events"], self.event_count, t0_us, t1_us)
        return self._inside_sensor(events)

    def _inside_sensor(self, events: np.ndarray, first_index: int | None = None) -> np.ndarray:
        """``events``, or a SessionError naming the first one outside the sensor."""
        outside = (events["x"] >= self.width) | (events["y"] >= self.height)
        if len(events) and outside.any():
            at = int(np.argmax(outside))
            event = events[at]
            where = "" if first_index is None else f"event {first_index + at}, "
            raise SessionError(
                f"{self.h5_path}: {where}t={int(event['t'])} µs lies at x={int(event['x'])}, "
                f"y={int(event['y'])}, outside the {self.width}x{self.height} sensor: the file "
                "is damaged; restore it from a copy"
            )
        return events

    def events_by_index(self, first: int, stop: int) -> np.ndarray:
        """Stored events ``first`` (included) to ``stop`` (excluded), in time order."""
        stop = min(stop, self.event_count)
        out = np.empty(max(stop - first, 0), dtype=EVENT_DTYPE)
        for name in EVENT_FIELDS if len(out) else ():
            out[name] = self._h5["events"][name][first : first + len(out)]
        return out

    def imu(self) -> np.ndarray:
        """Every IMU sample (``IMU_DTYPE``)."""
        return _read_records(self._h5.get("imu"), IMU_DTYPE)

    def triggers(self) -> np.ndarray:
        """Every trigger (``TRIGGER_DTYPE``)."""
        return _read_records(self._h5.get("triggers"), TRIGGER_DTYPE)

    def has_bins(self, b: int) -> bool:
        """True when bins for ``b`` are stored for every frame."""
        path = bins_path(b)
        return path in self._h5 and complete_rows(self._h5[path], _BINS_FIELDS) >= self.frame_count

    def stored_bins(self) -> list[int]:
        """Every b whose bins are stored, ascending."""
        return sorted(int(name[1:]) for name in self._h5.get("bins", {}))

    def window_event_counts(self) -> np.ndarray | None:
        """Events inside each frame's exposure window (from the stored bins), or None."""
        for b in self.stored_bins():
            if self.has_bins(b):
                return self._h5[bins_path(b)]["event_count"][: self.frame_count]
        return None

    def bins(self, b: int, *, recompute: bool = False) -> SessionBins:
        """Bins for ``b`` bins per exposure; computed from the stored events and saved if missing.

        Args:
            b: bins per exposure, >= 1.
            recompute: compute and save them again even when stored.

        Raises:
            SessionError: bad ``b``, or bins must be written and the session needs repair first.
        """
        if int(b) != b or b < 1:
            raise SessionError(f"number of bins {b!r} must be a whole number >= 1")
        if recompute or not self.has_bins(b):
            self._compute_bins(b)
        group = self._h5[bins_path(b)]
        count = self.frame_count
        arrays = {name: group[name][:count] for name in _BINS_FIELDS}
        return SessionBins(b=int(b), **arrays)

    def poses(self, b: int) -> SessionPoses | None:
        """Poses stored for ``b``, or None when none were estimated yet."""
        path = poses_path(b)
        if path not in self._h5:
            return None
        group = self._h5[path]
        return SessionPoses(
            c2w=group["c2w"][()],
            registered=group["registered"][()],
            intrinsics=group["intrinsics"][()],
            distortion=np.asarray(group["intrinsics"].attrs.get("distortion", []), np.float64),
            bounds=group["bounds"][()],
            time_us=group["time_us"][()] if "time_us" in group else None,
        )

    def write_poses(self, b: int, poses: SessionPoses) -> None:
        """Store (or replace) the poses for ``b``.

        Raises:
            SessionError: shapes do not match the session, or it needs repair first.
        """
        expected = (self.frame_count, b + 1)
        if poses.c2w.shape != (*expected, 4, 4) or poses.registered.shape != expected:
            raise SessionError(
                f"poses for b={b} must be c2w {(*expected, 4, 4)} and registered {expected}, got "
                f"{poses.c2w.shape} and {poses.registered.shape}"
            )
        if poses.time_us is not None and poses.time_us.shape != expected:
            raise SessionError(
                f"pose times for b={b} must be {expected}, got {poses.time_us.shape}"
            )
        if poses.intrinsics.shape != (4,) or poses.bounds.shape != (2,):
            raise SessionError("intrinsics must be (fx, fy, cx, cy) and bounds (near, far)")
        with self._writable() as h5:
            path = poses_path(b)
            if path in h5:
                del h5[path]
            group = h5.create_group(path)
            try:
                with storage_errors(self.h5_path):
                    _write_pose_datasets(group, poses)
            except BaseException:  # a full disk, Ctrl-C, SIGTERM
                del h5[path]  # never listed as stored when partial
                raise

    def calibration(self) -> SensorCalibration | None:
        """The sensor calibration measured from this recording, or None before it is.

        Raises:
            SessionError: the stored calibration cannot be read.
        """
        return read_calibration(self._h5)

    def write_calibration(self, calibration: SensorCalibration) -> None:
        """Store (or replace) the sensor calibration.

        Raises:
            SessionError: the pixel factors do not fit the sensor, or it needs repair first.
        """
        shape = (self.height, self.width)
        for name in ("pixel_factor_on", "pixel_factor_off"):
            if getattr(calibration, name).shape not in (shape, (0, 0)):
                raise SessionError(
                    f"calibration {name} has shape {getattr(calibration, name).shape}, the "
                    f"sensor is {shape}"
                )
        with self._writable() as h5:
            write_calibration(h5, calibration)

    def _compute_bins(self, b: int) -> None:
        """Bin every frame's exposure for ``b`` from the stored events and save the result."""
        table = self.frames_table()
        with writer_lock(self.folder, f"adding bins for b={b}"), self._writable() as h5:
            if bins_path(b) in h5:
                del h5[bins_path(b)]
            group = create_bins_group(h5, b=b, width=self.width, height=self.height, live=False)
            columns = dict(group.items())  # opened once: see SessionWriter._enter_swmr
            try:
                for start_us, end_us in zip(
                    table.exposure_start_us, table.exposure_end_us, strict=True
                ):
                    check_free_space(self.folder, f"adding bins for b={b}")
                    window = self.events_between(int(start_us), int(end_us))
                    exposure = bin_exposure(
                        window, int(start_us), int(end_us), b, self.width, self.height
                    )
                    with storage_errors(self.h5_path):
                        write_bins_row(columns, exposure)
            except BaseException as error:  # a full disk, Ctrl-C, SIGTERM
                del h5[bins_path(b)]  # never listed as stored when partial
                if not isinstance(error, OSError):
                    raise
                raise SessionError(
                    f"{self.h5_path}: bins for b={b} not stored: {error.strerror or error}"
                ) from error

    def require_writable(self) -> None:
        """Refuse, before any work, to add to a recording that was not closed cleanly.

        Raises:
            SessionError: the session needs repair first (the message gives the command).
        """
        if self.needs_repair:
            raise SessionError(
                f"{self.folder}: the recording was not closed cleanly; run "
                f"`seecap inspect {self.folder} --repair` before adding bins, a calibration or "
                "poses"
            )

    def _writable(self) -> _WritableSession:
        """Reopen the HDF5 file for writing for the duration of a ``with`` block."""
        self.require_writable()
        return _WritableSession(self)


def _write_pose_datasets(group: h5py.Group, poses: SessionPoses) -> None:
    group["c2w"] = np.asarray(poses.c2w, np.float64)
    group["registered"] = np.asarray(poses.registered, np.bool_)
    group["intrinsics"] = np.asarray(poses.intrinsics, np.float64)
    group["intrinsics"].attrs["distortion"] = np.asarray(poses.distortion, np.float64)
    group["bounds"] = np.asarray(poses.bounds, np.float64)
    if poses.time_us is not None:
        group["time_us"] = np.asarray(poses.time_us, np.int64)


READER_WAIT_S = 120.0
"""How long a writer waits for other processes reading ``session.h5`` to close it (HDF5 locks
a file that any process has open), so that work already done is not lost to a reader."""


def _open_for_writing(path: Path) -> h5py.File:
    """``path`` opened ``r+``, waiting up to :data:`READER_WAIT_S` while a reader holds it."""
    deadline = time.monotonic() + READER_WAIT_S
    while True:
        try:
            return h5py.File(path, "r+")
        except OSError as error:
            locked = "unable to lock file" in str(error) or "errno = 11" in str(error)
            if not locked or time.monotonic() > deadline:
                if locked:
                    raise OSError(
                        errno.EAGAIN,
                        f"another process has it open for {READER_WAIT_S:.0f} s (close "
                        "`seecap inspect`, HDFView or a notebook reading it, then run this again)",
                    ) from error
                raise
            time.sleep(0.5)


def _exit_on_terminate(signum: int, frame) -> None:
    raise SystemExit(128 + signum)


class _WritableSession:
    """Context that swaps a session's read-only HDF5 handle for a writable one and back.

    A file open for writing that is never closed stays flagged as open, and HDF5 then refuses
    to read it; so while it is open, SIGTERM (``kill``, a scheduler's stop) ends the process
    through the normal exit path, which closes the file, as Ctrl-C already does (unless the
    program handles SIGTERM itself, as the ``seecap`` verbs do).
    """

    def __init__(self, session: Session):
        self._session = session
        self._previous_handler = None

    def __enter__(self) -> h5py.File:
        in_main = threading.current_thread() is threading.main_thread()
        if in_main and signal.getsignal(signal.SIGTERM) in (signal.SIG_DFL, None):
            self._previous_handler = signal.signal(signal.SIGTERM, _exit_on_terminate)
        self._session._h5.close()
        try:
            self._session._h5 = _open_for_writing(self._session.h5_path)
        except OSError as error:
            self._session._h5 = h5py.File(self._session.h5_path, "r")
            self._restore_handler()
            raise SessionError(f"{self._session.h5_path}: cannot write ({error})") from error
        return self._session._h5

    def __exit__(self, exc_type, exc, tb) -> None:
        self._session._h5.close()
        self._session._h5 = h5py.File(self._session.h5_path, "r")
        self._restore_handler()

    def _restore_handler(self) -> None:
        if self._previous_handler is not None:
            signal.signal(signal.SIGTERM, self._previous_handler)
            self._previous_handler = None


def _read_records(group: h5py.Group | None, dtype: np.dtype) -> np.ndarray:
    """Read the column datasets of ``group`` (None: missing) into one structured array."""
    count = complete_rows(group, dtype.names)
    out = np.empty(count, dtype=dtype)
    for name in dtype.names if count else ():
        out[name] = group[name][:count]
    return out
