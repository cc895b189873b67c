"""Incremental ``session.h5`` writer in SWMR mode: a killed process leaves a readable file."""

from __future__ import annotations

import errno
import os
import re
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np

from davis_io.bins import ExposureBins
from davis_io.errors import SessionError
from davis_io.session.layout import (
    FILE_FORMAT,
    FRAME_TIMES,
    append_rows,
    bins_path,
    create_image_dataset,
    create_layout,
    read_events_between,
    write_bins_row,
)
from davis_io.types import Frame

__all__ = [
    "MIN_FREE_BYTES",
    "RESERVE_NAME",
    "abandoned_files",
    "SessionWriter",
    "check_free_space",
    "not_written",
    "output_errors",
    "storage_errors",
]

_DEFAULT_IMAGE_DTYPE = np.uint16
_DEFAULT_BIT_DEPTH = 10
_EVENT_BLOCK = 1 << 18
"""Events are written in blocks of at least this many (two chunks): small appends to a compressed
chunk would recompress it every time."""
_CHUNK_CACHE_BYTES = 64 << 20
_KINDS = ("events", "imu", "triggers")
MIN_FREE_BYTES = 16 << 20
"""A recording stops while this much is still free on its disk: room to store what is held,
close ``session.h5`` and write ``session.json``. HDF5 itself cannot survive a full disk (its
chunk writes then fail where nothing can catch them)."""

RESERVE_NAME = ".space-reserve"
"""A file of :data:`MIN_FREE_BYTES` allocated while a session is written and removed before it
closes: another process may fill the disk between two checks of the free space, and an HDF5
file closed on a full disk is left in a state that crashes the process when its objects are
freed; the reserve gives the close its room back."""
_ERRNO = re.compile(r"errno = (\d+)")


@contextmanager
def storage_errors(path: Path) -> Iterator[None]:
    """Turn HDF5's failures to write ``path`` into ``OSError`` with the C library's errno.

    h5py raises a RuntimeError for a failed flush or close, the errno only in its message.
    """
    try:
        yield
    except RuntimeError as error:
        found = _ERRNO.search(str(error))
        number = int(found.group(1)) if found else errno.EIO
        raise OSError(number, os.strerror(number), str(path)) from error


def not_written(path: Path, why: str, then: str = "run the command again") -> OSError:
    """The error for an output that was not written: the file, why, its disk's free space.

    ``errno`` is ENOSPC when under 1 MB is free, else EIO; the message ends with ``then``.
    """
    path = Path(path)
    free_mb = shutil.disk_usage(path.parent).free / 1e6
    return OSError(
        errno.ENOSPC if free_mb < 1.0 else errno.EIO,
        f"not written ({why.splitlines()[0] if why else 'unknown'}; {free_mb:.0f} MB free on its "
        f"disk): free some space, then {then}",
        str(path),
    )


@contextmanager
def output_errors(
    path: Path, then: str = "run the command again", kinds: tuple[type, ...] = (OSError,)
) -> Iterator[None]:
    """Turn a failure (of ``kinds``) to write ``path`` into :func:`not_written`'s error."""
    try:
        yield
    except kinds as error:
        raise not_written(path, getattr(error, "strerror", None) or str(error), then) from error


def check_free_space(folder: Path, what: str, files_bytes: int = 0) -> None:
    """Raise ``OSError(ENOSPC)`` unless ``files_bytes`` and :data:`MIN_FREE_BYTES` are free.

    Args:
        folder: a folder on the disk to check.
        what: what would be written, for the message.
        files_bytes: what it is about to write, when known in advance.
    """
    free, needed = shutil.disk_usage(folder).free, MIN_FREE_BYTES + files_bytes
    if free < needed:
        files = f"{files_bytes / 1e6:.0f} MB for its files and " if files_bytes else ""
        raise OSError(
            errno.ENOSPC,
            f"{free / 1e6:.1f} MB free on the disk holding {folder}, and {what} needs "
            f"{needed / 1e6:.0f} MB ({files}{MIN_FREE_BYTES / 1e6:.0f} MB to close them intact): "
            "free some space or write to another disk",
            str(folder),
        )


_ABANDONED: list[SessionWriter] = []
"""Writers whose file HDF5 failed to close (a disk another process filled at that moment).

HDF5 keeps such a file open with writes it cannot do; freeing its objects, or the library's own
clean-up at exit, then crashes the process. They are kept here until the process ends without
that clean-up (:func:`davis_io.cli.console`); what was flushed before stays readable and
``seecap inspect SESSION --repair`` closes the session."""


def abandoned_files() -> list[Path]:
    """The files of this process that HDF5 could not close (see :data:`_ABANDONED`)."""
    return [writer.path for writer in _ABANDONED]


def _allocate(path: Path, size: int) -> None:
    """Create ``path`` holding ``size`` bytes of real disk space (not a sparse file)."""
    descriptor = os.open(path, os.O_CREAT | os.O_WRONLY | os.O_TRUNC | os.O_NOFOLLOW, 0o600)
    try:
        try:
            os.posix_fallocate(descriptor, 0, size)
        except OSError as error:
            if error.errno not in (errno.EOPNOTSUPP, errno.EINVAL):
                raise
            block = bytes(1 << 20)  # a file system without fallocate: write the zeros
            for _ in range(-(-size // len(block))):
                os.write(descriptor, block)
    finally:
        os.close(descriptor)


class SessionWriter:
    """Append events, IMU samples, triggers and binned frames to a new ``session.h5``.

    The file works in HDF5's single-writer/multiple-reader (SWMR) mode from the start: every
    :meth:`flush` writes what is held and leaves a file that readers (and a later
    ``Session.open`` after a crash) see in a consistent state. SWMR forbids creating datasets,
    so the one dataset whose dtype only the first frame tells, ``/frames/image``, is created by
    closing the file, reopening it, creating the dataset and entering SWMR mode again.
    Events are held until a block of ``_EVENT_BLOCK`` is complete or the next flush.
    """

    def __init__(self, path: Path, *, width: int, height: int, b: int):
        self.path = Path(path)
        self.width, self.height, self.b = width, height, b
        self._held: dict[str, list[np.ndarray]] = {kind: [] for kind in _KINDS}
        self._held_events = 0
        self._closing = False
        self._reserve = self.path.parent / RESERVE_NAME
        try:
            check_free_space(self.path.parent, "a recording")
            _allocate(self._reserve, MIN_FREE_BYTES)
            self._h5 = h5py.File(self.path, "w", libver=FILE_FORMAT, rdcc_nbytes=_CHUNK_CACHE_BYTES)
        except OSError as error:
            self._reserve.unlink(missing_ok=True)
            raise SessionError(f"cannot create {self.path}: {error}") from error
        with storage_errors(self.path):
            create_layout(self._h5, width=width, height=height, b=b)
            self._enter_swmr()
        self.events_written = 0
        self.frames_written = 0

    @property
    def events_received(self) -> int:
        """Events written plus events held for the next block."""
        return self.events_written + self._held_events

    def write_events(self, events: np.ndarray) -> None:
        """Append events (``EVENT_DTYPE``, sorted, later than every event written before)."""
        if len(events) == 0:
            return
        self._held["events"].append(events)
        self._held_events += len(events)
        if self._held_events >= _EVENT_BLOCK:
            with storage_errors(self.path):
                self._spill("events")

    def write_imu(self, imu: np.ndarray) -> None:
        """Append IMU samples (``IMU_DTYPE``); written at the next flush."""
        if len(imu):
            self._held["imu"].append(imu)

    def write_triggers(self, triggers: np.ndarray) -> None:
        """Append triggers (``TRIGGER_DTYPE``); written at the next flush."""
        if len(triggers):
            self._held["triggers"].append(triggers)

    def write_frame(self, frame: Frame, *, events_lost: bool, bins: ExposureBins) -> None:
        """Append one frame with its loss flag and its bins (bins first, timestamps last).

        Raises:
            SessionError: the image is not a ``(height, width)`` array of the session's depth.
        """
        if frame.image.shape != (self.height, self.width):
            raise SessionError(
                f"frame image of shape {frame.image.shape} does not fit the {self.width}x"
                f"{self.height} sensor: sessions store full raw frames (no ROI, no demosaicing)"
            )
        if "image" not in self._columns["frames"]:
            self._add_image_dataset(frame.image.dtype, frame.bit_depth)
        frames = self._columns["frames"]
        if not np.can_cast(frame.image.dtype, frames["image"].dtype, "safe"):
            raise SessionError(
                f"frame {self.frames_written} is {frame.image.dtype}, earlier frames were "
                f"{frames['image'].dtype}: a session holds frames of one bit depth"
            )
        self._check_space()
        with storage_errors(self.path):
            write_bins_row(self._columns["bins"], bins)
            append_rows(frames["image"], frame.image[None].astype(frames["image"].dtype))
            append_rows(frames["events_lost"], np.array([events_lost]))
            for name in FRAME_TIMES:
                append_rows(frames[name], np.array([getattr(frame, name)], dtype=np.int64))
        self.frames_written += 1

    def read_events(self, t0_us: int, t1_us: int) -> np.ndarray:
        """Events written or held so far with ``t0_us <= t <= t1_us``."""
        self.flush()
        return read_events_between(self._h5["events"], self.events_written, t0_us, t1_us)

    def flush(self) -> None:
        """Write everything held and make it durable and visible to readers."""
        with storage_errors(self.path):
            for kind in _KINDS:
                self._spill(kind)
            self._h5.flush()

    def close(self) -> None:
        """Write what is still held, flush and close the file (idempotent).

        A session without frames still gets its (empty, 16-bit) ``/frames/image``. What is
        held is written even below the free-space margin: the margin is there for it.
        """
        self._closing = True
        self._reserve.unlink(missing_ok=True)  # the room to close in, whatever filled the disk
        if not self._h5.id.valid:
            return
        try:
            with storage_errors(self.path):
                try:
                    self.flush()
                    if "image" not in self._columns["frames"]:
                        self._add_image_dataset(_DEFAULT_IMAGE_DTYPE, _DEFAULT_BIT_DEPTH)
                finally:
                    if self._h5.id.valid:
                        self._h5.close()
        except OSError:
            if self._h5.id.valid:  # HDF5 could not close it: never let it touch the file again
                _ABANDONED.append(self)
            raise

    def _spill(self, kind: str) -> None:
        """Append the held records of one kind to their datasets."""
        held = self._held[kind]
        if not held:
            return
        self._check_space()
        self._held[kind] = []
        for name, dataset in self._columns[kind].items():
            append_rows(dataset, np.concatenate([records[name] for records in held]))
        if kind == "events":
            self._held_events = 0
            self.events_written += sum(len(records) for records in held)

    def _check_space(self) -> None:
        if not self._closing:
            check_free_space(self.path.parent, "a recording")

    def _enter_swmr(self) -> None:
        """Enter SWMR mode and open every dataset written to, held until the file closes.

        A dataset opened for one write and freed after it would flush its chunks on a disk that
        may have filled meanwhile, outside any handler: HDF5 then crashes the process.
        """
        self._h5.swmr_mode = True
        groups = {kind: kind for kind in ("frames", *_KINDS)} | {"bins": bins_path(self.b)}
        self._columns = {kind: dict(self._h5[name].items()) for kind, name in groups.items()}

    def _add_image_dataset(self, image_dtype, bit_depth: int) -> None:
        """Close, reopen, create ``/frames/image`` and return to SWMR mode."""
        self.flush()
        self._h5.close()
        self._h5 = h5py.File(self.path, "a", libver=FILE_FORMAT, rdcc_nbytes=_CHUNK_CACHE_BYTES)
        create_image_dataset(
            self._h5,
            width=self.width,
            height=self.height,
            image_dtype=image_dtype,
            bit_depth=bit_depth,
        )
        self._enter_swmr()
