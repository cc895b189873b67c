"""The live status line of a recording and the per-frame quality warnings."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from davis_io.bins import ExposureBins
from davis_io.session.manifest import DropCounters
from davis_io.types import Frame

__all__ = [
    "BLUR_EVENTS_PER_BIN",
    "BLUR_PIXEL_FRACTION",
    "CLIPPED_FRACTION",
    "RecordingStatus",
    "format_status_line",
    "frame_warnings",
]

CLIPPED_FRACTION = 0.25
"""Warn when more than this fraction of a frame is saturated or underexposed."""
_DARK_LEVEL = 0.02
"""Underexposed: at or below 2 % of full scale."""
_BRIGHT_LEVEL = 0.98
"""Saturated: at or above 98 % of full scale."""
BLUR_EVENTS_PER_BIN = 4
"""A pixel that fired more than this many events per bin on average (more than ``4 * b`` in the
exposure) changed its brightness by over e^1.2 = 3.3x (Θ = 0.3) between neighbouring latent
frames: more motion than the ``b + 1`` latent frames of the blur model represent."""
BLUR_PIXEL_FRACTION = 0.10
"""Warn of strong blur when more than this fraction of the pixels did so."""


@dataclass
class RecordingStatus:
    """A snapshot of a running recording for the status line.

    Attributes:
        elapsed_s: wall-clock seconds since the recording started.
        frames: frames written.
        events: events written.
        events_per_s: event rate over the last status interval.
        bytes_written: size of ``session.h5`` on disk.
        queue_fill: fraction of the packet queue in use, 0..1.
        drops: loss counters so far.
        exposure_measured_us: median exposure of the frames written (None before the first).
        warnings: per-frame warnings raised since the previous snapshot.
    """

    elapsed_s: float = 0.0
    frames: int = 0
    events: int = 0
    events_per_s: float = 0.0
    bytes_written: int = 0
    queue_fill: float = 0.0
    drops: DropCounters = field(default_factory=DropCounters)
    exposure_measured_us: int | None = None
    warnings: list[str] = field(default_factory=list)


def format_status_line(status: RecordingStatus) -> str:
    """One line, e.g. ``12.3 s | 61 frames | 1.20 Mev/s | 45.1 MB | queue 3% | drops 0 | ...``."""
    exposure = (
        "exposure -"
        if status.exposure_measured_us is None
        else f"exposure {status.exposure_measured_us / 1000:.2f} ms"
    )
    drops = status.drops
    return (
        f"{status.elapsed_s:7.1f} s | {status.frames} frames | "
        f"{status.events_per_s / 1e6:.2f} Mev/s | {status.bytes_written / 1e6:.1f} MB | "
        f"queue {status.queue_fill:.0%} | drops {drops.total_events} ev "
        f"{drops.queue_frames} fr | {exposure}"
    )


def frame_warnings(index: int, frame: Frame, bins: ExposureBins) -> list[str]:
    """Quality warnings for one recorded frame (empty when it looks fine).

    Checks: saturated fraction (>= 98 % of full scale), underexposed fraction (<= 2 %), blur
    stronger than the bins represent (many pixels fired more than :data:`BLUR_EVENTS_PER_BIN`
    events per bin, summed over the ``b`` bins), and an exposure with no event at all (nothing
    moved, or the DVS is off).
    """
    full_scale = float((1 << frame.bit_depth) - 1)
    level = frame.image.astype(np.float32) / full_scale
    where = f"frame {index} (exposure {frame.exposure_us / 1000:.2f} ms)"
    warnings = []
    saturated = float(np.mean(level >= _BRIGHT_LEVEL))
    if saturated > CLIPPED_FRACTION:
        warnings.append(f"{where}: {saturated:.0%} saturated: shorten the exposure")
    dark = float(np.mean(level <= _DARK_LEVEL))
    if dark > CLIPPED_FRACTION:
        warnings.append(f"{where}: {dark:.0%} underexposed: lengthen the exposure or add light")
    if bins.event_count == 0:
        warnings.append(f"{where}: no events during the exposure (no motion, or DVS off)")
    else:
        b = len(bins.raw)
        fired = np.abs(bins.raw.astype(np.int32)).sum(axis=0)
        busy = float(np.mean(fired > BLUR_EVENTS_PER_BIN * b))
        if busy > BLUR_PIXEL_FRACTION:
            warnings.append(
                f"{where}: blur too strong for b={b} bins ({busy:.0%} of pixels fired "
                f"> {BLUR_EVENTS_PER_BIN * b} events): use more bins, a shorter "
                "exposure or slower motion"
            )
    return warnings
