"""The cores the thread pools of davis_io's stages use: all this process may run on, or fewer.

The calibration's sensor-wide factor fit and COLMAP's feature extraction run on
:func:`usable_cores` threads; a caller that shares the machine (``seecap fit --threads N``)
bounds them with :func:`cores_limited`, as it bounds torch's and BLAS's pools.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

__all__ = ["cores_limited", "usable_cores"]

_LIMIT: ContextVar[int] = ContextVar("cores_limit", default=0)


def usable_cores() -> int:
    """The cores this process may run on, at most the limit set by :func:`cores_limited`."""
    cores = len(os.sched_getaffinity(0))
    limit = _LIMIT.get()
    return min(cores, limit) if limit > 0 else cores


@contextmanager
def cores_limited(count: int) -> Iterator[None]:
    """Within the block, :func:`usable_cores` is at most ``count`` (0: no limit)."""
    token = _LIMIT.set(count)
    try:
        yield
    finally:
        _LIMIT.reset(token)
