"""Run one command and write its own time, CPU and peak memory as JSON (a small parent).

    python tools/benchlib/measure.py USAGE.json COMMAND [ARGUMENT ...]

On Linux a child's peak resident memory starts at its parent's peak when it execs, so a
benchmark that has imported torch would inflate every child it measures. This launcher is a
fresh interpreter with nothing loaded; it starts the command, reaps it with ``os.wait4`` (whose
usage is that child's alone) and writes ``{"returncode", "wall_s", "cpu_s", "peak_rss_mb"}``.
On Linux the launcher and the command are killed when their parent dies, so a benchmark killed
mid-run leaves no fit behind still writing its run folder. Standard library only, so it loads
nothing else.
"""

from __future__ import annotations

import ctypes
import json
import os
import signal
import subprocess
import sys
import time

__all__ = ["die_with_parent", "main"]

PR_SET_PDEATHSIG = 1
"""Linux ``prctl`` option: the signal this process receives when its parent exits."""


def die_with_parent() -> None:
    """Have Linux kill the calling process when its parent exits (nothing elsewhere)."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):
        pass


def main(argv: list[str]) -> int:
    """Run ``argv[1:]``, write its usage to ``argv[0]``; return its exit code."""
    if len(argv) < 2:
        print("usage: measure.py USAGE.json COMMAND [ARGUMENT ...]", file=sys.stderr)
        return 2
    die_with_parent()
    start = time.monotonic()
    process = subprocess.Popen(argv[1:], preexec_fn=die_with_parent)
    _, status, usage = os.wait4(process.pid, 0)
    process.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen.wait
    record = {
        "returncode": process.returncode,
        "wall_s": time.monotonic() - start,
        "cpu_s": usage.ru_utime + usage.ru_stime,
        "peak_rss_mb": usage.ru_maxrss * 1024 / 1e6,  # Linux reports kilobytes
    }
    with open(argv[0], "w") as file:
        json.dump(record, file)
    return process.returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
