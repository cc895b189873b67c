"""Typed errors of the capture side; each message says what was wrong, where, and what to do."""

from __future__ import annotations

import errno

__all__ = [
    "DavisIOError",
    "DeviceError",
    "FormatError",
    "SeecapError",
    "SessionError",
    "UsageError",
    "describe_error",
]


class SeecapError(Exception):
    """Base of every error raised on purpose by seecap (caught by the ``seecap`` CLI).

    Attributes:
        exit_status: the process exit status the CLI gives it, or None for the usual (1, or 2
            for a usage error).
    """

    exit_status: int | None = None


class DavisIOError(SeecapError):
    """Base of every error raised on purpose by ``davis_io``."""


class UsageError(DavisIOError):
    """A value given by the user (flag, option, argument) is not acceptable."""


class FormatError(DavisIOError):
    """A file is not what its reader expects.

    Attributes:
        path: the file, when known.
        offset: byte offset of the problem, when known.
    """

    def __init__(self, message: str, *, path: str | None = None, offset: int | None = None):
        where = []
        if path is not None:
            where.append(str(path))
        if offset is not None:
            where.append(f"byte offset {offset}")
        super().__init__(f"{': '.join(where)}: {message}" if where else message)
        self.path = path
        self.offset = offset


class DeviceError(DavisIOError):
    """A camera could not be found, opened, configured or read."""


class SessionError(DavisIOError):
    """A session folder is missing, incomplete or inconsistent."""


def describe_error(error: BaseException) -> str:
    """One line for any failure: what was wrong, where, and what to do.

    A seecap error is its own message; a file that could not be read or written is named with
    the reason; anything else is a bug, and the line says how to report it.
    """
    if isinstance(error, SeecapError):
        return str(error)
    if isinstance(error, OSError) and error.filename is not None:
        return f"{error.filename}: {error.strerror or error}"
    if isinstance(error, OSError) and error.errno == errno.ENOSPC:
        return f"disk full ({error}): free some space"
    return (
        f"{type(error).__name__}: {error} (this is a bug: run again with `seecap --debug ...` "
        "for the traceback and report it)"
    )
