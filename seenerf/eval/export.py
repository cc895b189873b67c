"""Files of a fit: OpenEXR HDR, PNG previews, LDR brackets, CRF plot, metrics, transforms."""

from __future__ import annotations

import json
import math
from pathlib import Path

import cv2
import numpy as np
import OpenEXR

__all__ = [
    "OPENCV_TO_OPENGL",
    "crf_plot",
    "tone_mapped_preview",
    "transforms_json",
    "write_exr",
    "write_json",
    "write_png",
]

OPENCV_TO_OPENGL = np.diag([1.0, -1.0, -1.0, 1.0])
"""Right-multiply an OpenCV camera-to-world (x right, y down, z forward) to get OpenGL axes."""

_CHANNEL_COLOURS = ((60, 60, 230), (60, 180, 60), (230, 90, 40))  # BGR of the R, G, B curves
_MONO_COLOUR = (70, 70, 70)  # BGR of a monochrome sensor's one curve


def write_exr(path: Path, image: np.ndarray, metadata: dict[str, str | float]) -> None:
    """Write ``(H, W, 3)`` RGB or ``(H, W, 1)`` Y float32 linear radiance with header metadata."""
    path.parent.mkdir(parents=True, exist_ok=True)
    name = "RGB" if image.shape[-1] == 3 else "Y"
    pixels = np.ascontiguousarray(image if name == "RGB" else image[..., 0], np.float32)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, **metadata}
    with OpenEXR.File(header, {name: pixels}) as exr:
        exr.write(str(path))


def write_png(path: Path, image: np.ndarray) -> None:
    """Write an RGB or grey image in [0, 1] as 8-bit PNG (clipped, rounded)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    pixels = np.round(np.clip(image, 0.0, 1.0) * 255).astype(np.uint8)
    if pixels.ndim == 3 and pixels.shape[-1] == 3:
        pixels = pixels[..., ::-1]
    cv2.imwrite(str(path), np.ascontiguousarray(pixels.squeeze()))


def tone_mapped_preview(hdr: np.ndarray) -> np.ndarray:
    """``ln(1 + 5000 x) / ln(5001)`` of ``x = hdr / max(hdr)``: a viewable image in [0, 1]."""
    peak = float(hdr.max()) if np.isfinite(hdr).all() and hdr.max() > 0 else 1.0
    return np.log1p(5000.0 * np.clip(hdr / peak, 0.0, 1.0)) / math.log(5001.0)


def crf_plot(
    path: Path,
    learned: tuple[np.ndarray, np.ndarray],
    true: tuple[np.ndarray, np.ndarray] | None,
    channels: tuple[int, ...] = (0, 1, 2),
    size: tuple[int, int] = (640, 420),
) -> None:
    """Draw response curves: learned solid, true dashed (when known); x = ln(radiance x s).

    Args:
        path: PNG to write.
        learned: ``(K,)`` log exposures and ``(K, 3)`` learned LDR values.
        true: the same for the true response (``(K, 1)`` for a monochrome one), or None.
        channels: the curves the sensor's pixels go through; one alone is drawn grey.
        size: ``(width, height)`` of the image in pixels.
    """
    width, height = size
    canvas = np.full((height, width, 3), 255, np.uint8)
    xs = np.concatenate([learned[0]] + ([true[0]] if true is not None else []))
    low, high = float(xs.min()), float(xs.max())
    margin = 40

    def to_pixel(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        px = margin + (x - low) / max(high - low, 1e-9) * (width - 2 * margin)
        py = height - margin - np.clip(y, 0, 1) * (height - 2 * margin)
        return np.stack([px, py], axis=-1).round().astype(np.int32)

    cv2.rectangle(canvas, (margin, margin), (width - margin, height - margin), (0, 0, 0), 1)
    for channel in channels:
        colour = _CHANNEL_COLOURS[channel] if len(channels) > 1 else _MONO_COLOUR
        points = to_pixel(learned[0], learned[1][:, channel])
        cv2.polylines(canvas, [points], False, colour, 2, cv2.LINE_AA)
        if true is not None:
            dashed = to_pixel(true[0], true[1][:, min(channel, true[1].shape[1] - 1)])
            for start in range(0, len(dashed) - 1, 2):
                cv2.line(
                    canvas, tuple(dashed[start]), tuple(dashed[start + 1]), colour, 1, cv2.LINE_AA
                )
    label = f"ln(radiance x s) from {low:.1f} to {high:.1f}; solid learned, dashed true"
    cv2.putText(canvas, label, (margin, height - 12), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 0), 1)
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), canvas)


def transforms_json(
    c2w: np.ndarray, intrinsics: np.ndarray, image_size: tuple[int, int], file_paths: list[str]
) -> dict:
    """A ``transforms.json`` (nerfstudio / instant-ngp style, OpenGL camera axes) of views.

    Args:
        c2w: ``(N, 4, 4)`` OpenCV camera-to-world.
        intrinsics: fx, fy, cx, cy.
        image_size: ``(height, width)``.
        file_paths: relative image path of each view.
    """
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    frames = [
        {"file_path": name, "transform_matrix": (pose @ OPENCV_TO_OPENGL).tolist()}
        for name, pose in zip(file_paths, np.asarray(c2w, float), strict=True)
    ]
    return {
        "camera_model": "OPENCV",
        "fl_x": fx,
        "fl_y": fy,
        "cx": cx,
        "cy": cy,
        "w": image_size[1],
        "h": image_size[0],
        "frames": frames,
    }


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
    path.write_text(json.dumps(clean(payload), indent=2) + "\n")
