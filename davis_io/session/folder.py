"""The session folder on disk: its default name, safe creation and emptying, plain run names."""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path

from davis_io.errors import UsageError
from davis_io.session.lock import LOCK_NAME, writer_lock
from davis_io.session.manifest import MANIFEST_NAME

__all__ = [
    "check_limits",
    "check_preview",
    "default_session_name",
    "empty_folder",
    "new_session_folder",
    "plain_name",
]


def default_session_name(now: datetime | None = None) -> str:
    """Folder name from the UTC time, e.g. ``session-20260314-153009``."""
    return (now or datetime.now(UTC)).strftime("session-%Y%m%d-%H%M%S")


_PLAIN_NAME = re.compile(r"\w[\w.+-]{0,99}")
"""One folder name: a letter, digit or underscore first, then those, ``.``, ``+`` or ``-``."""


def plain_name(name: str, option: str) -> str:
    """``name`` if it names one folder inside another (no separator, no ``..``, not absolute).

    Raises:
        UsageError: anything else (the message names the option and what a name may hold).
    """
    if not isinstance(name, str) or not _PLAIN_NAME.fullmatch(name):
        raise UsageError(
            f"{option} {name!r} is not a plain name: use up to 100 letters, digits, '_', '.', "
            "'+' or '-', starting with a letter, digit or '_' (no '/', no '..'), e.g. fast-full"
        )
    return name


def empty_folder(folder: Path) -> None:
    """Remove everything inside ``folder`` except its writer lock (which its holder keeps).

    Symbolic links are removed as links: nothing they point at is touched.
    """
    for child in Path(folder).iterdir():
        if child.name == LOCK_NAME:
            continue
        if child.is_dir() and not child.is_symlink():
            shutil.rmtree(child)
        else:
            child.unlink()


@contextmanager
def new_session_folder(out_dir: Path, *, overwrite: bool) -> Iterator[Path]:
    """Hold the writer lock of an empty session folder; replace a session only when ``overwrite``.

    The lock is taken before anything is removed and kept while the caller records, so a
    session another process is recording, fitting or repairing is never replaced. A folder this
    call created is removed again when the caller fails before writing its manifest.

    Raises:
        UsageError: the folder is a file, belongs to another user, holds files and
            ``overwrite`` is False, or holds files but no session.
        SessionBusy: another process writes the session (the message names it).
    """
    folder = Path(out_dir)
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"{folder} is a file: give a folder name with --out")
    if folder.is_dir() and folder.stat().st_uid != os.geteuid():
        raise UsageError(f"{folder} belongs to another user: choose another --out")
    created = not folder.exists()
    if not created and _holds_files(folder):
        _check_replaceable(folder, overwrite)  # refused before a lock file is left there
    started = False
    try:
        with writer_lock(folder, "recording"):
            if _holds_files(folder):
                _check_replaceable(folder, overwrite)
                empty_folder(folder)
            started = True
            try:
                yield folder
            except BaseException:
                if not (folder / MANIFEST_NAME).exists():
                    empty_folder(folder)
                raise
    except BaseException:
        if created and started and not (folder / MANIFEST_NAME).exists():
            shutil.rmtree(folder, ignore_errors=True)
        raise


def _holds_files(folder: Path) -> bool:
    return any(child.name != LOCK_NAME for child in folder.iterdir())


def _check_replaceable(folder: Path, overwrite: bool) -> None:
    if not overwrite:
        raise UsageError(
            f"{folder} already exists and is not empty: choose another --out, or pass "
            "--overwrite to replace the session in it"
        )
    if not (folder / MANIFEST_NAME).exists():
        raise UsageError(
            f"{folder} holds files but no {MANIFEST_NAME}: --overwrite only replaces a "
            "session folder; choose another --out"
        )


def check_limits(bins: int, frames: int | None, duration_us: int | None) -> None:
    """Raise UsageError for a bad number of bins, frame limit or duration."""
    if int(bins) != bins or bins < 1:
        raise UsageError(f"--bins {bins!r} must be a whole number >= 1 (4 or 6 are usual)")
    if frames is not None and frames < 1:
        raise UsageError(f"--frames {frames!r} must be >= 1")
    if duration_us is not None and duration_us < 1:
        raise UsageError(f"--duration {duration_us!r} µs must be positive")


def check_preview(preview: Path | str | None) -> Path | None:
    """The preview path as a Path; raise UsageError unless it is a .png in an existing folder."""
    if preview is None:
        return None
    path = Path(preview)
    if path.suffix.lower() != ".png":
        raise UsageError(f"--preview {path}: give a .png file name")
    if not path.parent.is_dir():
        raise UsageError(f"--preview {path}: folder {path.parent} does not exist")
    return path
