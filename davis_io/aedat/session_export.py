"""A recorded session written back out as an AEDAT 4.0 file."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from davis_io.aedat.aedat4_write import write_aedat4
from davis_io.session import Session
from davis_io.session.export import DAVIS_BIT_DEPTH, session_packets, session_source_info

__all__ = ["export_aedat4"]


def export_aedat4(session_path: Path | str, out_path: Path | str) -> Path:
    """Write a session's events, frames, IMU samples and triggers to an AEDAT 4.0 file.

    Returns:
        The file written.
    """
    with Session.open(session_path) as session:
        bit_depth = DAVIS_BIT_DEPTH
        if session.frame_count and session.frame(0).image.dtype == np.uint16:
            bit_depth = session.frame(0).bit_depth
        return write_aedat4(
            session_packets(session),
            out_path,
            info=session_source_info(session),
            frame_bit_depth=bit_depth,
        )
