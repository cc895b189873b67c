"""How many threads a fit computes with: one bound on every CPU thread pool it uses.

The pools are torch's, the BLAS under numpy and OpenCV's.

Bounding torch alone is not enough when fits run side by side: numpy's OpenBLAS keeps a thread
per core that spins after each call. Two one-thread fits on two cores trained 5.8 steps/s each
with those threads about, 8.1 without.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import cv2
import torch
from threadpoolctl import threadpool_limits

__all__ = [
    "CoreWatch",
    "busy_cores",
    "choose_threads",
    "limit_threads",
    "threads_beside",
    "threads_for",
]

LOOK_S = 0.3
"""How long the machine is watched to see how busy its cores are."""


def limit_threads(count: int | None) -> None:
    """Use at most ``count`` threads in each pool for the rest of the process (None: as is)."""
    if count is None:
        return
    torch.set_num_threads(count)
    threadpool_limits(limits=count)
    cv2.setNumThreads(count)


def threads_for(cores: int, busy: float) -> int:
    """Threads for a fit on ``cores`` cores of which ``busy`` (a fraction of cores) are in use.

    A core counts as free when less than half of it is busy; at least one thread. On a shared
    machine each thread more than the free cores only waits for a busy one, and the others wait
    for it at every step.
    """
    return max(1, min(cores, cores - int(busy + 0.5)))


def _cpu_times(stat: str) -> tuple[int, int]:
    """``(busy, total)`` jiffies of all CPUs from ``/proc/stat``'s text."""
    fields = [int(v) for v in stat.splitlines()[0].split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)  # idle and waiting for I/O
    total = sum(fields[:8])  # guest time is counted inside user time already
    return total - idle, total


def threads_beside(others: float) -> int:
    """Threads for a fit beside ``others`` cores of other work, on the cores it may run on."""
    return threads_for(len(os.sched_getaffinity(0)), others)


class CoreWatch:
    """The cores' worth of work other processes do, between two looks at the machine.

    Reads ``/proc/stat`` (every process's work) and leaves out this process's own CPU time, so
    a fit can look while it trains.
    """

    def __init__(self, stat: Path = Path("/proc/stat")):
        self.stat = stat
        self.last = self._look()

    def _look(self) -> tuple[int, int, float] | None:
        try:
            busy, total = _cpu_times(self.stat.read_text())
        except (OSError, ValueError, IndexError):
            return None
        return busy, total, time.process_time()

    def others(self) -> float | None:
        """Cores other work kept busy since the last look; None where unreadable or too soon."""
        now, last = self._look(), self.last
        self.last = now
        if now is None or last is None or now[1] <= last[1]:
            return None
        cores = os.cpu_count() or 1
        busy = cores * (now[0] - last[0]) / (now[1] - last[1])
        wall_s = (now[1] - last[1]) / (cores * os.sysconf("SC_CLK_TCK"))
        return max(0.0, busy - (now[2] - last[2]) / wall_s)


def busy_cores(look_s: float = LOOK_S, stat: Path = Path("/proc/stat")) -> float | None:
    """How many cores' worth of other work the machine did while watched (None: unreadable)."""
    watch = CoreWatch(stat)
    if watch.last is None:
        return None
    time.sleep(look_s)
    return watch.others()


def choose_threads(requested: int | None) -> tuple[int, str]:
    """The thread count of a fit and a line saying why.

    A count ``requested`` is taken as given; None uses the cores this process may run on that
    other work leaves free.
    """
    cores = len(os.sched_getaffinity(0))
    if requested is not None:
        return requested, f"threads: {requested} (as asked) on {cores} cores"
    busy = busy_cores()
    if busy is None:
        return cores, f"threads: {cores}, one per core (how busy they are is unknown here)"
    count = threads_beside(busy)
    return count, f"threads: {count} of {cores} cores ({busy:.1f} cores busy with other work)"
