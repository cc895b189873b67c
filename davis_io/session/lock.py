"""One writer at a time per session folder (or run folder): an advisory lock the kernel releases.

A writer holds ``fcntl.flock`` on ``<folder>/.writer.lock`` for as long as it writes and keeps
its process id, what it does and its start time in the file. A second writer gets a
:class:`SessionBusy` error naming the holder; a lock left by a killed process is free again
(the kernel dropped it with the process), so it is simply taken. Locks are re-entrant within a
process. The lock file is opened without following a symbolic link and must be a regular file
of the user's own, so that nobody can make a writer truncate another file through it.
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import stat
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from davis_io.errors import SessionError

__all__ = ["LOCK_NAME", "SessionBusy", "writer_lock"]

LOCK_NAME = ".writer.lock"

_held: dict[Path, int] = {}
"""Folders this process holds, and how deep."""


class SessionBusy(SessionError):
    """Another process is writing the same session (or run) folder."""


def _holder(path: Path) -> str:
    try:
        facts = json.loads(path.read_text())
        return (
            f"process {facts['pid']} ({facts['command']}, since "
            f"{time.strftime('%H:%M:%S', time.localtime(facts['started']))})"
        )
    except (OSError, ValueError, KeyError):
        return "another process"


@contextmanager
def writer_lock(folder: Path | str, purpose: str) -> Iterator[None]:
    """Hold the writer lock of ``folder`` (created if missing) while inside.

    Args:
        folder: a session folder, or a run folder inside it.
        purpose: what this writer does, for the message another writer gets.

    Raises:
        SessionBusy: another process holds it (the message names it and what to do).
        SessionError: the lock file is a symbolic link, not a plain file, or another user's.
    """
    folder = Path(folder).resolve()
    if _held.get(folder):
        _held[folder] += 1
        try:
            yield
        finally:
            _held[folder] -= 1
        return
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / LOCK_NAME
    handle = _open_lock_file(path)
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise SessionBusy(
                f"{folder} is being written by {_holder(path)}; wait for it to finish or stop "
                "it, then run this again"
            ) from None
        handle.seek(0)
        handle.truncate()
        facts = {"pid": os.getpid(), "command": purpose, "started": time.time()}
        handle.write(json.dumps(facts))
        handle.flush()
        _held[folder] = 1
        try:
            yield
        finally:
            _held.pop(folder, None)
    finally:
        handle.close()  # closing releases the lock


def _open_lock_file(path: Path):
    """The lock file opened for writing: never through a symbolic link, only the user's own."""
    flags = os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC
    try:
        descriptor = os.open(path, flags, 0o644)
    except OSError as error:
        if error.errno == errno.ELOOP:
            raise SessionError(
                f"{path} is a symbolic link: a writer lock must be a plain file; remove the "
                "link, then run this again"
            ) from None
        raise SessionError(f"cannot open the writer lock {path}: {error.strerror}") from None
    facts = os.fstat(descriptor)
    if not stat.S_ISREG(facts.st_mode) or facts.st_uid != os.geteuid():
        os.close(descriptor)
        raise SessionError(
            f"{path} is not a plain file of this user's: remove it (or write a copy of the "
            "session of your own), then run this again"
        )
    os.set_blocking(descriptor, True)
    return open(descriptor, "r+", encoding="utf-8")  # noqa: SIM115 - held until the block ends
