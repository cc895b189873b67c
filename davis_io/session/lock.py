"""One writer at a time per session folder (or run folder): an advisory lock the kernel releases.

A writer holds ``fcntl.flock`` on ``<folder>/.writer.lock`` for as long as it writes and keeps
its process id, what it does and its start time in the file. A second writer gets a
:class:`SessionBusy` error naming the holder; a lock left by a killed process is free again
(the kernel dropped it with the process), so it is simply taken. Fits share the lock of their
session (each writes only its own run folder, under that folder's exclusive lock), and so keep
out anything that rewrites the recording (``record --overwrite``, a repair, a calibration).
Locks are re-entrant within a process. The lock file is opened without following a symbolic
link and must be a regular file of the user's own, so that nobody can make a writer truncate
another file through it.
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
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from davis_io.errors import SessionError

__all__ = ["LOCK_NAME", "SessionBusy", "refuse_if_written", "writer_lock"]

LOCK_NAME = ".writer.lock"


@dataclass
class _Hold:
    """A lock this process holds: its open file, how deep, and whether it is exclusive."""

    handle: TextIO
    depth: int
    exclusive: bool


_held: dict[Path, _Hold] = {}
"""Folders this process holds."""


class SessionBusy(SessionError):
    """Another process is writing the same session (or run) folder."""


def _holders(path: Path) -> str:
    """Who holds the lock, from the facts each holder wrote (dead processes left out)."""
    try:
        lines = path.read_text().splitlines()
    except OSError:
        return "another process"
    found = []
    for line in lines:
        try:
            facts = json.loads(line)
            os.kill(int(facts["pid"]), 0)  # still running?
        except (ValueError, KeyError, TypeError, ProcessLookupError, PermissionError):
            continue
        since = time.strftime("%H:%M:%S", time.localtime(facts["started"]))
        found.append(f"process {facts['pid']} ({facts['command']}, since {since})")
    return ", ".join(found) or "another process"


@contextmanager
def writer_lock(folder: Path | str, purpose: str, *, shared: bool = False) -> Iterator[None]:
    """Hold the writer lock of ``folder`` (created if missing) while inside.

    Args:
        folder: a session folder, or a run folder inside it.
        purpose: what this writer does, for the message another writer gets.
        shared: share the lock with other shared holders (fits that read the recording and
            write only their own run folder): they exclude every exclusive writer, not each
            other.

    Raises:
        SessionBusy: another process holds it (the message names it and what to do).
        SessionError: the lock file is a symbolic link, not a plain file, or another user's.
    """
    folder = Path(folder).resolve()
    hold = _held.get(folder)
    if hold is not None:
        with _nested(folder, hold, shared):
            yield
        return
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / LOCK_NAME
    handle = _open_lock_file(path)
    try:
        _take(handle, path, folder, shared)
        facts = json.dumps({"pid": os.getpid(), "command": purpose, "started": time.time()})
        if shared:
            handle.seek(0, os.SEEK_END)
        else:
            handle.seek(0)
            handle.truncate()
        handle.write(facts + "\n")
        handle.flush()
        _held[folder] = _Hold(handle, 1, not shared)
        try:
            yield
        finally:
            _held.pop(folder, None)
    finally:
        handle.close()  # closing releases the lock


def _take(handle: TextIO, path: Path, folder: Path, shared: bool) -> None:
    try:
        fcntl.flock(handle, (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB)
    except BlockingIOError:
        raise SessionBusy(
            f"{folder} is being written by {_holders(path)}; wait for it to finish or stop "
            "it, then run this again"
        ) from None


def refuse_if_written(folder: Path | str) -> None:
    """Raise :class:`SessionBusy` if another process writes ``folder`` now.

    A reader's check: nothing is created, and nothing is held after it.

    Raises:
        SessionBusy: another process holds the folder's lock exclusively.
    """
    folder = Path(folder).resolve()
    path = folder / LOCK_NAME
    if folder in _held or not path.is_file() or path.is_symlink():
        return
    try:
        handle = open(path, encoding="utf-8")  # noqa: SIM115 - closed below
    except OSError:
        return
    with handle:
        _take(handle, path, folder, shared=True)


@contextmanager
def _nested(folder: Path, hold: _Hold, shared: bool) -> Iterator[None]:
    """A lock this process holds already; a shared one is made exclusive while inside."""
    upgrade = not shared and not hold.exclusive
    if upgrade:
        _take(hold.handle, folder / LOCK_NAME, folder, shared=False)
        hold.exclusive = True
    hold.depth += 1
    try:
        yield
    finally:
        hold.depth -= 1
        if upgrade:
            fcntl.flock(hold.handle, fcntl.LOCK_SH)
            hold.exclusive = False


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
