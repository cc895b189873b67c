"""``seecap bins``: bins for another b, computed from a session's stored events."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from davis_io.session.layout import bins_path
from davis_io.session.store import Session

__all__ = ["compute_session_bins"]


def compute_session_bins(path: Path | str, b: int, *, force: bool = False) -> str:
    """Make sure ``/bins/b{b}`` holds every frame's bins; return a one-paragraph summary.

    Args:
        path: the session folder.
        b: bins per exposure.
        force: recompute them even when already stored.

    Raises:
        SessionError: bad ``b``, or the session must be repaired first.
    """
    with Session.open(path) as session:
        stored_before = session.has_bins(b)
        bins = session.bins(b, recompute=force)
        frames = len(bins.event_count)
    action = "already stored" if stored_before and not force else "computed"
    lines = [f"{path}: {bins_path(b)} {action} for {frames} frames"]
    if frames:
        span_ms = np.diff(bins.split_us, axis=1) / 1000
        lines.append(
            f"events per exposure: median {int(np.median(bins.event_count))}, "
            f"min {int(bins.event_count.min())}; bin length median {np.median(span_ms):.2f} ms"
        )
    return "\n".join(lines)
