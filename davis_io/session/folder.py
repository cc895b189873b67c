"""The session folder on disk: its default name, safe creation, and the recording options."""

from __future__ import annotations

import shutil
from datetime import UTC, datetime
from pathlib import Path

from davis_io.errors import UsageError
from davis_io.session.manifest import MANIFEST_NAME

__all__ = ["check_limits", "check_preview", "default_session_name", "prepare_session_folder"]


def default_session_name(now: datetime | None = None) -> str:
    """Folder name from the UTC time, e.g. ``session-20260314-153009``."""
    return (now or datetime.now(UTC)).strftime("session-%Y%m%d-%H%M%S")


def prepare_session_folder(out_dir: Path, *, overwrite: bool) -> Path:
    """Create an empty session folder; replace an existing session only when ``overwrite``.

    Raises:
        UsageError: the folder holds files and ``overwrite`` is False, or it is not a session.
    """
    folder = Path(out_dir)
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"{folder} is a file: give a folder name with --out")
    if folder.exists() and any(folder.iterdir()):
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
        shutil.rmtree(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return folder


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
