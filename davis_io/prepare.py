"""Making a session ready to fit: the sensor measured, then the poses estimated, when missing."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from davis_io.calibration.session_calibration import session_calibration
from davis_io.poses.estimate import estimate_poses
from davis_io.session import Session

__all__ = ["prepare_session"]


def prepare_session(session_dir: Path | str, b: int, log: Callable[[str], None] = print) -> float:
    """Calibrate the sensor and estimate poses for ``b`` if the session lacks them.

    Args:
        session_dir: the session folder.
        b: bins per exposure of the poses.
        log: receives one line per step taken.

    Returns:
        The seconds spent.

    Raises:
        ColmapError: the poses could not be estimated (with advice).
        SessionError, UsageError: the session cannot be read or written.
    """
    start = time.perf_counter()
    with Session.open(session_dir) as session:
        if session.calibration() is None:
            log("measuring the sensor from the recording")
            calibration = session_calibration(session, progress=log)
            log(calibration.summary())
        if session.poses(b) is None:
            log(f"estimating poses (b={b})")
            log(estimate_poses(session, b=b).summary())
    return time.perf_counter() - start
