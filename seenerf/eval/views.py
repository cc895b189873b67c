"""A fitted model's views: rendered as HDR and LDR images at chosen poses, and written as files."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from davis_io.geometry import nerfstudio_transforms
from seenerf.eval.export import (
    tone_mapped_preview,
    write_exr,
    write_json,
    write_png,
)
from seenerf.model.model import SeeNerfModel
from seenerf.render.rays import pixel_coordinates, rays_through

__all__ = [
    "PAPER_EXPOSURES_S",
    "RenderedViews",
    "render_log_image",
    "render_views",
    "write_views",
]

PAPER_EXPOSURES_S = (0.001, 0.004, 0.016, 0.064, 0.256)
"""The paper's LDR bracket, used when neither the config nor the truth names exposures."""

_LUMINANCE = np.array([0.2126, 0.7152, 0.0722], np.float32)


@dataclass
class RenderedViews:
    """Rendered views in the fit's frame.

    Attributes:
        c2w: ``(V, 4, 4)`` poses rendered (fit frame).
        hdr: linear HDR images ``(H, W, C)``; ``ldr[e]`` the images at ``exposures_s[e]``.
        render_s: seconds per view.
    """

    c2w: np.ndarray
    exposures_s: tuple[float, ...]
    hdr: list[np.ndarray] = field(default_factory=list)
    ldr: list[list[np.ndarray]] = field(default_factory=list)
    render_s: float = 0.0


@torch.inference_mode()
def render_log_image(
    model: SeeNerfModel,
    c2w: np.ndarray,
    intrinsics: np.ndarray,
    image_size: tuple[int, int],
    chunk: int = 4096,
    distortion: np.ndarray | None = None,
) -> np.ndarray:
    """Rendered log radiance ``(H, W, 3)`` of one camera, in chunks of rays.

    Args:
        model: a fitted model (evaluated without jitter or noise).
        c2w: ``(4, 4)`` camera-to-world in the model's frame, OpenCV axes.
        intrinsics: fx, fy, cx, cy.
        image_size: ``(height, width)``.
        chunk: rays per rendering call; a few thousand keep the per-sample tensors in cache
            (32k-ray chunks were up to 9x slower on two busy cores).
        distortion: the lens's OpenCV coefficients: the view is rendered in the camera's own
            model (None or empty: a pinhole).
    """
    height, width = image_size
    parameter = next(model.parameters())
    pose = torch.as_tensor(np.asarray(c2w), dtype=torch.float32, device=parameter.device)
    k = torch.as_tensor(np.asarray(intrinsics), dtype=torch.float32, device=parameter.device)
    lens = None if distortion is None else torch.as_tensor(distortion, device=k.device)
    x, y = pixel_coordinates(k, image_size, lens)
    out = []
    for start in range(0, x.numel(), chunk):
        origins, directions = rays_through(pose, x[start : start + chunk], y[start : start + chunk])
        out.append(model.render_log_radiance(origins, directions))
    return torch.cat(out).reshape(height, width, 3).cpu().numpy()


@torch.no_grad()
def render_views(
    model: SeeNerfModel,
    c2w: np.ndarray,
    intrinsics: np.ndarray,
    image_size: tuple[int, int],
    exposures_s: tuple[float, ...],
    monochrome: bool,
    distortion: np.ndarray | None = None,
) -> RenderedViews:
    """HDR and LDR images of each pose; a monochrome sensor's views are luminance ``(H, W, 1)``.

    ``distortion``: the lens's OpenCV coefficients (None or empty: a pinhole).
    """
    model.eval()
    views = RenderedViews(np.asarray(c2w), tuple(exposures_s), ldr=[[] for _ in exposures_s])
    start = time.perf_counter()
    for pose in views.c2w:
        log_image = torch.as_tensor(
            render_log_image(model, pose, intrinsics, image_size, distortion=distortion)
        )
        if monochrome:
            hdr = model.hdr_from_log(log_image).numpy() @ _LUMINANCE
            log_lum = torch.log(torch.as_tensor(hdr).clamp(min=1e-30))[..., None].expand(-1, -1, 3)
            views.hdr.append(hdr[..., None])
            for index, ldr in enumerate(model.ldr_images(log_lum, exposures_s)):
                views.ldr[index].append(ldr[..., :1].numpy())
        else:
            views.hdr.append(model.hdr_from_log(log_image).numpy())
            for index, ldr in enumerate(model.ldr_images(log_image, exposures_s)):
                views.ldr[index].append(ldr.numpy())
    views.render_s = (time.perf_counter() - start) / max(len(views.c2w), 1)
    return views


def write_views(
    views: RenderedViews,
    run_dir: Path,
    intrinsics: np.ndarray,
    image_size: tuple[int, int],
    metadata: dict,
    distortion: np.ndarray | None = None,
) -> None:
    """EXR + tone-mapped PNG per view, LDR PNGs per exposure, and ``transforms.json``.

    ``distortion``: the lens's OpenCV coefficients the views were rendered with (None: none).
    """
    names = []
    for index, hdr in enumerate(views.hdr):
        name = f"{index:03d}"
        write_exr(run_dir / "renders" / "hdr" / f"{name}.exr", hdr, metadata)
        write_png(run_dir / "renders" / "hdr" / f"{name}.png", tone_mapped_preview(hdr))
        for exposure, images in zip(views.exposures_s, views.ldr, strict=True):
            write_png(run_dir / "renders" / "ldr" / f"{exposure:g}" / f"{name}.png", images[index])
        names.append(f"renders/hdr/{name}.png")
    write_json(
        run_dir / "transforms.json",
        nerfstudio_transforms(
            views.c2w,
            intrinsics,
            np.zeros(0) if distortion is None else distortion,
            image_size,
            names,
        ),
    )
