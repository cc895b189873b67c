"""Whole-view rendering and the similarity that maps truth poses into the fit's frame."""

from __future__ import annotations

import numpy as np
import torch

from davis_io.geometry import Similarity, align_poses
from seenerf.data import TrainingData
from seenerf.model import SeeNerfModel
from seenerf.rays import camera_rays

__all__ = ["IDENTITY", "render_log_image", "truth_to_fit_frame"]

IDENTITY = Similarity(1.0, np.eye(3), np.zeros(3))
"""The similarity of a fit trained in the truth frame (the oracle)."""


@torch.inference_mode()
def render_log_image(
    model: SeeNerfModel,
    c2w: np.ndarray,
    intrinsics: np.ndarray,
    image_size: tuple[int, int],
    chunk: int = 4096,
) -> np.ndarray:
    """Rendered log radiance ``(H, W, 3)`` of one camera, in chunks of rays.

    Args:
        model: a fitted model (evaluated without jitter or noise).
        c2w: ``(4, 4)`` camera-to-world in the model's frame, OpenCV axes.
        intrinsics: fx, fy, cx, cy.
        image_size: ``(height, width)``.
        chunk: rays per rendering call; a few thousand keep the per-sample tensors in cache
            (32k-ray chunks were up to 9x slower on two busy cores).
    """
    height, width = image_size
    parameter = next(model.parameters())
    pose = torch.as_tensor(np.asarray(c2w), dtype=torch.float32, device=parameter.device)
    k = torch.as_tensor(np.asarray(intrinsics), dtype=torch.float32, device=parameter.device)
    v, u = torch.meshgrid(
        torch.arange(height, device=k.device), torch.arange(width, device=k.device), indexing="ij"
    )
    u, v = u.reshape(-1).float(), v.reshape(-1).float()
    out = []
    for start in range(0, u.numel(), chunk):
        origins, directions = camera_rays(
            pose, k, u[start : start + chunk], v[start : start + chunk]
        )
        out.append(model.render_log_radiance(origins, directions))
    return torch.cat(out).reshape(height, width, 3).cpu().numpy()


def truth_to_fit_frame(data: TrainingData) -> Similarity:
    """Similarity from the truth frame to the fit's (estimated) frame, from centres and axes.

    Aligns the estimated latent poses to the true poses at the same instants (camera centres
    and orientations, :func:`~davis_io.geometry.align_poses`) and inverts the result.
    Without truth, or with fewer than three distinct centres, the frames are taken to coincide.
    """
    if data.truth is None or data.truth.latent_c2w is None:
        return IDENTITY
    estimated = data.c2w.reshape(-1, 4, 4).astype(np.float64)
    true = data.truth.latent_c2w.reshape(-1, 4, 4).astype(np.float64)
    if len(estimated) < 3 or np.allclose(estimated[:, :3, 3], estimated[0, :3, 3]):
        return IDENTITY
    return align_poses(estimated, true).inverse()
