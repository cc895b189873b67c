"""Per-session records handed to readers: frame timestamps, bins of every frame, poses."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FramesTable", "SessionBins", "SessionPoses"]


@dataclass(frozen=True)
class FramesTable:
    """Per-frame timestamps (µs) and loss flags, all ``(F,)``."""

    exposure_start_us: np.ndarray
    exposure_end_us: np.ndarray
    readout_start_us: np.ndarray
    readout_end_us: np.ndarray
    events_lost: np.ndarray

    @property
    def exposure_us(self) -> np.ndarray:
        """Exposure durations in µs."""
        return self.exposure_end_us - self.exposure_start_us


@dataclass(frozen=True)
class SessionBins:
    """The bins of every frame for one ``b`` (see :class:`davis_io.bins.ExposureBins`).

    Attributes:
        b: bins per exposure.
        split_us: ``(F, b+1)`` int64 latent time points: exposure start, bin starts, exposure end.
        weights: ``(F, b+1)`` float64 trapezoid weights, rows sum to 1.
        raw: ``(F, b, H, W)`` int16 signed counts.
        calibrated: ``(F, b, H, W)`` float32 counts with the h() offsets, or with ``contrast``
            the ln intensity change of each bin (events weighted by their thresholds).
        event_count: ``(F,)`` int64 events inside each exposure window.
        contrast: ``calibrated`` is in ln units (:func:`~davis_io.session.contrast_bins`), not
            counts.
        settled: ``(F, b+1, H, W)`` bool, whether each pixel had fired all it owed at each
            latent time point (:func:`davis_io.settled.settled_points`); None unless asked.
        lead: ``(F, H, W)`` float32, with ``contrast``: each pixel's ln change from the first
            exposure of its stretch to the start of this one (the exposures' bins and the events
            between them), so that two latent points of one stretch differ by a known change;
            None for count bins.
        stretch: ``(F,)`` int64, with ``lead``: which unbroken stretch of the stream each
            exposure belongs to; a gap, or an exposure that lost events, starts a new one.
    """

    b: int
    split_us: np.ndarray
    weights: np.ndarray
    raw: np.ndarray
    calibrated: np.ndarray
    event_count: np.ndarray
    contrast: bool = False
    settled: np.ndarray | None = None
    lead: np.ndarray | None = None
    stretch: np.ndarray | None = None


@dataclass(frozen=True)
class SessionPoses:
    """Camera poses at the ``b + 1`` latent time points of every frame (OpenCV axes).

    Attributes:
        c2w: ``(F, b+1, 4, 4)`` float64 camera-to-world.
        registered: ``(F, b+1)`` bool, True where the pose was estimated (not interpolated).
        intrinsics: ``(4,)`` float64 fx, fy, cx, cy in pixels.
        distortion: ``(K,)`` float64 distortion coefficients (OpenCV order; may be empty).
        bounds: ``(2,)`` float64 near and far depth of the sparse points.
        time_us: ``(F, b+1)`` int64 the latent time points the poses belong to (the bins' at
            the time they were estimated), or None for poses stored without them (the stored
            bins' then).
    """

    c2w: np.ndarray
    registered: np.ndarray
    intrinsics: np.ndarray
    distortion: np.ndarray
    bounds: np.ndarray
    time_us: np.ndarray | None = None
