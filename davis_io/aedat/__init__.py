"""AEDAT 2.0 / 3.1 / 4.0 recordings as packet sources, and AEDAT 4.0 writing."""

from __future__ import annotations

from pathlib import Path

from davis_io.aedat.aedat2 import Aedat2Reader
from davis_io.aedat.aedat4_header import Compression
from davis_io.aedat.aedat4_read import Aedat4Reader, clip_packet
from davis_io.aedat.aedat4_write import Aedat4Writer, write_aedat4
from davis_io.aedat.aedat31 import Aedat31Reader
from davis_io.aedat.report import RecordingWarning
from davis_io.errors import FormatError
from davis_io.types import PacketSource

__all__ = [
    "Aedat2Reader",
    "Aedat31Reader",
    "Aedat4Reader",
    "Aedat4Writer",
    "Compression",
    "RecordingWarning",
    "clip_packet",
    "detect_format",
    "open_recording",
    "write_aedat4",
]

_READERS = {
    b"#!AER-DAT2.0": Aedat2Reader,
    b"#!AER-DAT3.1": Aedat31Reader,
    b"#!AER-DAT4.0": Aedat4Reader,
}


def detect_format(path: str | Path) -> str:
    """Return ``"2.0"``, ``"3.1"`` or ``"4.0"`` from the file's first line.

    Raises:
        FormatError: empty file, not an AEDAT file, or an AEDAT version this reader lacks.
    """
    with Path(path).open("rb") as file:
        start = file.read(12)
    if not start:
        raise FormatError("empty file: not an AEDAT recording", path=str(path), offset=0)
    if start in _READERS:
        return start[-3:].decode()
    if start.startswith(b"#!AER-DAT"):
        raise FormatError(
            f"AEDAT version {start[9:].decode('ascii', 'replace')!r} is not supported "
            "(supported: 2.0, 3.1, 4.0); convert it with DV or jAER",
            path=str(path),
            offset=9,
        )
    raise FormatError(
        f"first bytes {start!r} are not an AEDAT header ('#!AER-DAT<version>')",
        path=str(path),
        offset=0,
    )


def open_recording(path: str | Path, **options) -> PacketSource:
    """Open an AEDAT 2.0, 3.1 or 4.0 file as a packet source (format from its header).

    Args:
        path: the recording.
        **options: passed to the format's reader (e.g. ``accel_full_scale_g`` for AEDAT 2.0).

    Raises:
        FormatError: the file is not a readable AEDAT recording.
    """
    version = detect_format(path)
    return _READERS[f"#!AER-DAT{version}".encode()](path, **options)
