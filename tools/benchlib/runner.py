"""Runs one child process (argument list, no shell) and measures its own time, CPU and memory."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from benchlib.results import ProcessUsage

__all__ = ["python_command", "run_measured", "usage_from_json"]

POLL_S = 0.2
LAUNCHER = Path(__file__).resolve().parent / "measure.py"


def python_command(*arguments: str) -> list[str]:
    """``[this interpreter, -u, *arguments]`` (unbuffered, so logs are complete after a kill)."""
    return [sys.executable, "-u", *arguments]


def run_measured(
    argv: list[str], log_path: Path, *, cwd: Path | None = None, timeout_s: float | None = None
) -> ProcessUsage:
    """Run ``argv`` with stdout and stderr into ``log_path``; return what the child cost.

    The child is started by :mod:`benchlib.measure`, a bare interpreter that reaps it with
    ``os.wait4``: the peak memory is the child's alone, not this (larger) process's nor an
    earlier run's. Past ``timeout_s``, or when this call is interrupted (Ctrl-C, SIGTERM made an
    exception), the launcher's whole process group is killed.

    Args:
        argv: program and arguments (never a shell string).
        log_path: file receiving the child's output (its folder is created).
        cwd: working directory of the child.
        timeout_s: kill the child after this many seconds (None: no limit).
    """
    log_path.parent.mkdir(parents=True, exist_ok=True)
    usage_path = log_path.with_name(log_path.name + ".usage.json")
    usage_path.unlink(missing_ok=True)
    start = time.monotonic()
    timed_out = False
    with open(log_path, "wb") as log:
        launcher = subprocess.Popen(
            [sys.executable, str(LAUNCHER), str(usage_path), *argv],
            stdout=log,
            stderr=subprocess.STDOUT,
            cwd=cwd,
            start_new_session=True,
        )
        try:
            while launcher.poll() is None:
                if timeout_s is not None and time.monotonic() - start > timeout_s and not timed_out:
                    os.killpg(launcher.pid, signal.SIGKILL)  # the group this call created
                    timed_out = True
                time.sleep(POLL_S)
        except BaseException:  # interrupted: leave no child running on its own
            os.killpg(launcher.pid, signal.SIGKILL)
            launcher.wait()
            raise
    wall_s = time.monotonic() - start
    if not usage_path.exists():  # killed before the launcher could write
        return ProcessUsage(launcher.returncode, wall_s, float("nan"), float("nan"), timed_out)
    return usage_from_json(json.loads(usage_path.read_text()), timed_out)


def usage_from_json(measured: dict, timed_out: bool = False) -> ProcessUsage:
    """A :class:`ProcessUsage` from its JSON fields (the launcher's, or a saved one)."""
    return ProcessUsage(
        measured["returncode"],
        measured["wall_s"],
        measured["cpu_s"],
        measured["peak_rss_mb"],
        measured.get("timed_out", timed_out),
    )
