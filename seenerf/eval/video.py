"""A run's views as a video: at one exposure, or tone-mapped HDR (one scale for every frame)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from seenerf.errors import CheckpointError
from seenerf.eval.export import tone_mapped_preview
from seenerf.eval.views import RenderedViews

__all__ = ["VIDEO_FPS", "video_frames", "write_video"]

VIDEO_FPS = 24
"""Frames per second of a rendered path."""


def video_frames(views: RenderedViews, exposure_s: float | None) -> list[np.ndarray]:
    """``(H, W, C)`` images in [0, 1]: the LDR views at ``exposure_s``, or the HDR tone-mapped.

    HDR frames share one tone map (normalised by the brightest value of the whole path), so a
    bright object entering the view does not darken the rest.
    """
    if exposure_s is not None:
        index = int(np.argmin(np.abs(np.log(np.asarray(views.exposures_s) / exposure_s))))
        return list(views.ldr[index])
    peaks = [float(np.max(hdr)) for hdr in views.hdr]
    peak = max(peaks) if all(np.isfinite(peaks)) and max(peaks) > 0 else None
    return [tone_mapped_preview(hdr, peak) for hdr in views.hdr]


def write_video(path: Path, frames: list[np.ndarray], fps: int = VIDEO_FPS) -> Path:
    """Write ``frames`` (``(H, W, C)`` in [0, 1], C = 1 or 3 RGB) as an MP4 through OpenCV.

    MPEG-4 codes even sizes only: an odd width or height is padded by repeating the last column
    or row (a DAVIS346's 346 x 260 is written as it is).

    Raises:
        CheckpointError: no frames, or OpenCV cannot write an MP4 there.
    """
    path = Path(path)
    if not frames:
        raise CheckpointError(f"{path}: no views to make a video of")
    height, width = (size + size % 2 for size in frames[0].shape[:2])
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), fps, (width, height))
    if not writer.isOpened():
        raise CheckpointError(
            f"{path}: OpenCV cannot write an MP4 video here (is the folder writable? is the "
            "name's suffix .mp4?)"
        )
    try:
        for frame in frames:
            pixels = np.round(np.clip(frame, 0.0, 1.0) * 255).astype(np.uint8)
            pixels = pixels.reshape(*pixels.shape[:2], -1)
            pad = ((0, height - pixels.shape[0]), (0, width - pixels.shape[1]), (0, 0))
            pixels = np.pad(pixels, pad, mode="edge")
            if pixels.shape[2] == 1:
                writer.write(cv2.cvtColor(pixels[:, :, 0], cv2.COLOR_GRAY2BGR))
            else:
                writer.write(cv2.cvtColor(pixels, cv2.COLOR_RGB2BGR))
    finally:
        writer.release()
    return path
