"""Files of a fit: OpenEXR HDR, PNG previews, LDR brackets, CRF plot, metrics, transforms."""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import OpenEXR

from davis_io.session import not_written, output_errors

__all__ = [
    "tone_mapped_preview",
    "write_exr",
    "write_json",
    "write_png",
]

RENDER_AGAIN = "render the run again with `seecap render`"


def write_exr(path: Path, image: np.ndarray, metadata: dict[str, str | float]) -> None:
    """Write ``(H, W, 3)`` RGB or ``(H, W, 1)`` Y float32 linear radiance with header metadata."""
    path.parent.mkdir(parents=True, exist_ok=True)
    name = "RGB" if image.shape[-1] == 3 else "Y"
    pixels = np.ascontiguousarray(image if name == "RGB" else image[..., 0], np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, **metadata}
    # OpenEXR reports a full disk as a RuntimeError
    with output_errors(path, RENDER_AGAIN, (OSError, RuntimeError)):
        with OpenEXR.File(header, {name: pixels}) as exr:
            exr.write(str(path))


def write_png(path: Path, image: np.ndarray) -> None:
    """Write an RGB or grey image in [0, 1] as 8-bit PNG (clipped, rounded)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    pixels = np.round(np.clip(image, 0.0, 1.0) * 255).astype(np.uint8)
    if pixels.ndim == 3 and pixels.shape[-1] == 3:
        pixels = pixels[..., ::-1]
    if not cv2.imwrite(str(path), np.ascontiguousarray(pixels.squeeze())):
        raise not_written(path, "OpenCV could not write it", RENDER_AGAIN)


def tone_mapped_preview(hdr: np.ndarray, peak: float | None = None) -> np.ndarray:
    """``ln(1 + 5000 x) / ln(5001)`` of ``x = hdr / peak``: a viewable image in [0, 1].

    ``peak`` defaults to the image's own brightest value (a path of views passes one for all).
    """
    if peak is None:
        peak = float(hdr.max()) if np.isfinite(hdr).all() and hdr.max() > 0 else 1.0
    return np.log1p(5000.0 * np.clip(hdr / peak, 0.0, 1.0)) / math.log(5001.0)


def write_json(path: Path, payload: dict) -> None:
    """Write ``payload`` as indented JSON (NaN and inf become null)."""

    def clean(value):
        if isinstance(value, float) and not math.isfinite(value):
            return None
        if isinstance(value, dict):
            return {k: clean(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [clean(v) for v in value]
        return value

    path.parent.mkdir(parents=True, exist_ok=True)
    with output_errors(path):
        path.write_text(json.dumps(clean(payload), indent=2) + "\n")
