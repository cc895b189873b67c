"""Bins in light time, each bin's value the ln change of its light.

Each exposure's events are cut where the events of its light come and weighed by the thresholds
of their pixels; the events between exposures are summed too, so that any two latent points of an
unbroken stretch of the stream differ by a known change. Event processing on a session's stored
events, apart from its storage.
"""

from __future__ import annotations

import numpy as np

from davis_io.bins import bin_exposure
from davis_io.errors import SessionError
from davis_io.gaps import overlapping
from davis_io.session.calibration import SensorCalibration
from davis_io.session.records import SessionBins
from davis_io.session.store import Session
from davis_io.settled import SLEWING_INTERVALS, settled_points

__all__ = ["contrast_bins"]


def contrast_bins(
    session: Session, b: int, calibration: SensorCalibration, *, settled: bool = False
) -> SessionBins:
    """Bins of ``session`` for ``b`` in light time, whose ``contrast`` is each bin's ln change.

    Each exposure's events are cut ``calibration.latency_us`` later than the exposure (when the
    events of its light come), each event weighs its pixel's calibrated threshold, and the
    latent time points are moved back onto the exposure's clock. With ``settled`` the bins mark
    the points where a pixel was not firing at its dead-time limit (read from events two dead
    times beyond the exposure). ``lead`` adds up the exposures' bins and the weighted events
    between them from the first exposure of each unbroken ``stretch``. Computed, not stored.

    Raises:
        SessionError: bad ``b``.
    """
    if int(b) != b or b < 1:
        raise SessionError(f"number of bins {b!r} must be a whole number >= 1")
    table, latency = session.frames_table(), int(calibration.latency_us)
    width, height = session.width, session.height
    sizes = _event_sizes(calibration, (height, width))
    rows, points = [], []
    dead_time = calibration.dead_time_us
    margin = int(np.ceil(SLEWING_INTERVALS * dead_time)) if settled else 0
    starts = table.exposure_start_us.astype(np.int64) + latency
    ends = table.exposure_end_us.astype(np.int64) + latency
    broken = _broken_links(session, table.events_lost, starts, ends)
    lead = np.zeros((len(starts), height * width), np.float32)
    for index, (start, end) in enumerate(zip(starts.tolist(), ends.tolist(), strict=True)):
        window = session.events_between(start - margin, end + margin)
        row = bin_exposure(window, start, end, b, width, height, sizes)
        if index and not broken[index - 1]:
            after = int(ends[index - 1]) + 1
            between = session.events_between(after, start - 1) if start > after else window[:0]
            lead[index] = (
                lead[index - 1]
                + rows[-1].calibrated.sum(axis=0).reshape(-1)
                + _weighted_change(between, sizes, width, height)
            )
        rows.append(row)
        if settled:
            points.append(settled_points(window, row.split_us, width, height, dead_time))
    return SessionBins(
        b=int(b),
        split_us=np.stack([row.split_us for row in rows]) - latency,
        weights=np.stack([row.weights for row in rows]),
        raw=np.stack([row.raw for row in rows]),
        calibrated=np.stack([row.calibrated for row in rows]),
        event_count=np.array([row.event_count for row in rows], np.int64),
        contrast=True,
        settled=np.stack(points) if settled else None,
        lead=lead.reshape(-1, height, width),
        stretch=np.concatenate([[0], np.cumsum(broken)]).astype(np.int64)[: len(starts)],
    )


def _broken_links(
    session: Session, lost: np.ndarray, starts: np.ndarray, ends: np.ndarray
) -> np.ndarray:
    """``(F-1,)`` True where exposure ``i + 1`` does not continue ``i``'s stretch of the stream.

    The stretch breaks where the events between them fall in a gap, and on either side of an
    exposure that lost events (its own change is not known).
    """
    lost = np.asarray(lost, bool)
    across = overlapping(session.event_gaps(), ends[:-1], starts[1:])
    return across | lost[:-1] | lost[1:]


def _weighted_change(
    events: np.ndarray, sizes: tuple[np.ndarray, np.ndarray], width: int, height: int
) -> np.ndarray:
    """``(H * W,)`` the ln change ``events`` stand for, each weighed by its pixel's threshold."""
    pixel = events["y"].astype(np.int64) * width + events["x"]
    change = np.where(events["p"] > 0, sizes[0][pixel], -sizes[1][pixel])
    return np.bincount(pixel, weights=change, minlength=width * height)


def _event_sizes(
    calibration: SensorCalibration, shape: tuple[int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """The ln change each ON and each OFF event stands for, per flat pixel."""
    sizes = []
    for threshold, factors in (
        (calibration.threshold_on, calibration.pixel_factor_on),
        (calibration.threshold_off, calibration.pixel_factor_off),
    ):
        factors = factors if factors.shape == shape else np.ones(shape)
        sizes.append(threshold * np.asarray(factors, np.float64).reshape(-1))
    return sizes[0], sizes[1]
