"""What every AEDAT reader shares: the file it owns and warnings about recordings read anyway."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import BinaryIO

from davis_io.types import Closing

__all__ = ["FileReader", "RecordingWarning", "warn_note"]


class FileReader(Closing):
    """Base of the AEDAT readers: opens ``path`` for binary reading and closes it on exit.

    Attributes:
        path: the recording.
    """

    def __init__(self, path: str | Path):
        """Open ``path``; a subclass reads its header after this and calls ``close`` if it fails."""
        self.path = Path(path)
        self._file: BinaryIO = self.path.open("rb")

    def close(self) -> None:
        """Close the file."""
        self._file.close()


class RecordingWarning(UserWarning):
    """A recording was read with something skipped or missing; the message says what and where."""


def warn_note(message: str) -> str:
    """Emit ``message`` as a :class:`RecordingWarning` and return it for a packet's ``notes``."""
    warnings.warn(message, RecordingWarning, stacklevel=3)
    return message
