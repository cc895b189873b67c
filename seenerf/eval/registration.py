"""Test-time registration: a held-out view's pose refined photometrically against a fitted model.

A fit made from estimated poses lives in its own frame, known only up to the errors of those
poses; a held-out image's true pose, mapped into that frame by a similarity, lands a few pixels
off. Scoring at such a pose measures the pose error as much as the model. The usual protocol
for fields fitted from estimated poses (BARF, NeRF--) registers each held-out image to the
fitted model first: its 6-DoF pose, and only that, is optimised to match the image, coarse to
fine over an image pyramid so a shift of several pixels lies inside the basin.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import cv2
import numpy as np
import torch

from davis_io.geometry import rotation_error_deg
from seenerf.data.arrays import TrainingData
from seenerf.model.model import SeeNerfModel
from seenerf.render.rays import camera_rays

__all__ = ["RegistrationSpec", "pose_update", "register_test_poses", "register_view"]


@dataclass(frozen=True)
class RegistrationSpec:
    """How hard each held-out pose is refined.

    Attributes:
        levels: image-pyramid levels, coarsest first (a level-2 image is quarter size).
        steps: Adam steps per level.
        rays: random pixels per step.
        rotation_lr: step size of the rotation (radians).
        translation_lr: step size of the translation, in scene-box sides.
        final_lr_fraction: the step sizes fall geometrically over each level's steps to this
            fraction of their start, so the pose settles instead of jittering by about one
            step: 2e-3 rad is half a pixel at a focal length of 280 px.
    """

    levels: tuple[int, ...] = (2, 1, 0)
    steps: int = 25
    rays: int = 2048
    rotation_lr: float = 2e-3
    translation_lr: float = 2e-3
    final_lr_fraction: float = 0.05


def pose_update(c2w: torch.Tensor, rotation: torch.Tensor, translation: torch.Tensor):
    """``c2w`` moved by a rotation vector and a translation, both in the camera's own frame.

    Args:
        c2w: ``(4, 4)`` camera-to-world.
        rotation: ``(3,)`` axis times angle (radians).
        translation: ``(3,)`` camera-frame offset.
    """
    zero = rotation.new_zeros(())
    x, y, z = rotation.unbind()
    hat = torch.stack(
        [torch.stack([zero, -z, y]), torch.stack([z, zero, -x]), torch.stack([-y, x, zero])]
    )
    delta = torch.eye(4, dtype=c2w.dtype, device=c2w.device)
    delta = torch.cat(
        [torch.cat([torch.linalg.matrix_exp(hat), translation[:, None]], dim=1), delta[3:]]
    )
    return c2w @ delta


def _pyramid_level(image: np.ndarray, level: int) -> np.ndarray:
    for _ in range(level):
        image = cv2.pyrDown(image)
    return image.reshape(image.shape[0], image.shape[1], -1)


def register_view(
    model: SeeNerfModel,
    c2w: np.ndarray,
    intrinsics: np.ndarray,
    target_ldr: np.ndarray,
    exposure_s: float,
    spec: RegistrationSpec = RegistrationSpec(),
    seed: int = 0,
    distortion: np.ndarray | None = None,
) -> np.ndarray:
    """The pose near ``c2w`` whose rendering at ``exposure_s`` best matches ``target_ldr``.

    Args:
        model: a fitted model; its weights are not changed.
        c2w: ``(4, 4)`` starting camera-to-world in the model's frame.
        intrinsics: fx, fy, cx, cy of the full-size image.
        target_ldr: ``(H, W, C)`` image in [0, 1] taken at ``exposure_s`` (C = 1: luminance
            is compared with the mean of the rendered channels).
        exposure_s: the image's exposure.
        spec: pyramid, steps and step sizes.
        seed: seed of the pixel subsets.
        distortion: the lens's OpenCV coefficients (None or empty: a pinhole); the same at every
            pyramid level, which scales pixels only.

    Returns:
        ``(4, 4)`` refined camera-to-world (float32).
    """
    parameter = next(model.parameters())
    device = parameter.device
    pose = torch.as_tensor(np.asarray(c2w), dtype=torch.float32, device=device)
    rotation = torch.zeros(3, device=device, requires_grad=True)
    translation = torch.zeros(3, device=device, requires_grad=True)
    box_side = model.renderer.box.size
    optimiser = torch.optim.Adam(
        [
            {"params": [rotation], "lr": spec.rotation_lr},
            {"params": [translation], "lr": spec.translation_lr * box_side},
        ]
    )
    base_lrs = [group["lr"] for group in optimiser.param_groups]
    generator = torch.Generator().manual_seed(seed)
    lens = None if distortion is None else torch.as_tensor(distortion, device=device)
    was_training = model.training
    model.eval()
    frozen = [p.requires_grad for p in model.parameters()]
    for p in model.parameters():
        p.requires_grad_(False)
    try:
        for level in spec.levels:
            target = torch.as_tensor(
                _pyramid_level(np.asarray(target_ldr, np.float32), level), device=device
            )
            height, width = target.shape[:2]
            scale = 2.0**-level
            fx, fy, cx, cy = (float(v) for v in intrinsics)
            k = torch.tensor(
                [fx * scale, fy * scale, (cx + 0.5) * scale - 0.5, (cy + 0.5) * scale - 0.5],
                device=device,
            )
            for step in range(spec.steps):
                fall = spec.final_lr_fraction ** (step / max(spec.steps - 1, 1))
                for group, base in zip(optimiser.param_groups, base_lrs, strict=True):
                    group["lr"] = base * fall
                pixels = torch.randint(
                    0, height * width, (min(spec.rays, height * width),), generator=generator
                ).to(device)
                v, u = (pixels // width).float(), (pixels % width).float()
                moved = pose_update(pose, rotation, translation)
                origins, directions = camera_rays(moved, k, u, v, lens)
                log_radiance = model.render_log_radiance(origins, directions)
                ldr = model.ldr_from_log(log_radiance, exposure_s)
                truth = target.reshape(-1, target.shape[-1])[pixels]
                if truth.shape[-1] == 1:
                    ldr = ldr.mean(dim=-1, keepdim=True)
                loss = (ldr - truth).square().mean()
                optimiser.zero_grad(set_to_none=True)
                loss.backward()
                optimiser.step()
    finally:
        for p, flag in zip(model.parameters(), frozen, strict=True):
            p.requires_grad_(flag)
        model.train(was_training)
    with torch.no_grad():
        refined = pose_update(pose, rotation, translation)
    if not torch.isfinite(refined).all():
        return np.asarray(c2w, np.float32)
    return refined.cpu().numpy().astype(np.float32)


def register_test_poses(
    model: SeeNerfModel, data: TrainingData, c2w: np.ndarray
) -> tuple[np.ndarray, dict]:
    """Each held-out pose refined against its LDR image at the exposure nearest the training one.

    Returns:
        The refined ``(V, 4, 4)`` poses and a summary: the exposure used, how far each pose
        turned (degrees: every view's, the median and the largest) and the seconds per view.
    """
    exposures = np.asarray(data.test.exposures_s, np.float64)
    index = int(np.argmin(np.abs(np.log(exposures / model.reference_exposure_s))))
    start = time.perf_counter()
    refined = np.stack(
        [
            register_view(
                model,
                pose,
                data.intrinsics,
                data.test.ldr[view, index],
                float(exposures[index]),
                seed=view,
                distortion=data.distortion,
            )
            for view, pose in enumerate(c2w)
        ]
    )
    turned = rotation_error_deg(np.asarray(c2w)[:, :3, :3], refined[:, :3, :3])
    return refined, {
        "registered": True,
        "exposure_s": float(exposures[index]),
        "turned_deg": [float(angle) for angle in turned],
        "turned_deg_median": float(np.median(turned)),
        "turned_deg_max": float(np.max(turned)),
        "s_per_view": (time.perf_counter() - start) / max(len(c2w), 1),
    }
