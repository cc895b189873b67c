"""One bound on every CPU thread pool a fit uses: torch's, the BLAS under numpy, OpenCV's.

Bounding torch alone is not enough when fits run side by side: numpy's OpenBLAS keeps a thread
per core that spins after each call. Two one-thread fits on two cores trained 5.8 steps/s each
with those threads about, 8.1 without.
"""

from __future__ import annotations

import cv2
import torch
from threadpoolctl import threadpool_limits

__all__ = ["limit_threads"]


def limit_threads(count: int) -> None:
    """Use at most ``count`` threads in each pool for the rest of the process (0: the defaults)."""
    if count <= 0:
        return
    torch.set_num_threads(count)
    threadpool_limits(limits=count)
    cv2.setNumThreads(count)
