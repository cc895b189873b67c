"""The recording preview: latest frame beside its event image, written atomically as a PNG."""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np

from davis_io.errors import SessionError

__all__ = ["event_image", "preview_image", "write_preview"]

_ON_BGR = np.array([40, 40, 230], np.uint8)
_OFF_BGR = np.array([230, 120, 30], np.uint8)
_GAP_PX = 4


def event_image(net_counts: np.ndarray) -> np.ndarray:
    """Colour image of signed event counts: white background, red ON, blue OFF.

    Args:
        net_counts: ``(H, W)`` signed event count per pixel.

    Returns:
        ``(H, W, 3)`` uint8 BGR image.
    """
    image = np.full((*net_counts.shape, 3), 255, np.uint8)
    image[net_counts > 0] = _ON_BGR
    image[net_counts < 0] = _OFF_BGR
    return image


def preview_image(frame_image: np.ndarray, bit_depth: int, net_counts: np.ndarray) -> np.ndarray:
    """The frame (scaled to 8 bits, grey) and its event image side by side, BGR uint8."""
    gray = (frame_image.astype(np.float32) * (255.0 / ((1 << bit_depth) - 1))).clip(0, 255)
    left = cv2.cvtColor(gray.astype(np.uint8), cv2.COLOR_GRAY2BGR)
    gap = np.zeros((left.shape[0], _GAP_PX, 3), np.uint8)
    return np.concatenate([left, gap, event_image(net_counts)], axis=1)


def write_preview(path: Path, image: np.ndarray) -> None:
    """Write ``image`` to ``path`` atomically (a viewer never sees a half-written file).

    Raises:
        SessionError: OpenCV cannot encode the file type or the write failed.
    """
    path = Path(path)
    temporary = path.with_name(f".{path.stem}.tmp{path.suffix}")
    if not cv2.imwrite(str(temporary), image):
        raise SessionError(
            f"cannot write the preview {path}: use a .png file name in a writable folder"
        )
    os.replace(temporary, path)
