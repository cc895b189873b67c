"""Forward-facing scenes in the normalised device coordinates (NDC) of a reference camera.

When every camera looks roughly the same way, as a hand waving a camera at a scene does, a
world-aligned box spends most of a grid field's texels on space no camera sees and as many on
the far wall as on the nearest object. In a reference camera's NDC (the parameterisation NeRF
uses for forward-facing LLFF scenes, written here for OpenCV axes, z forward), ``x / z`` and
``y / z`` span the image and ``z' = 1 - 2 near / z`` runs linearly in disparity from the near
plane (-1) to infinity (+1): a texel covers about the same number of pixels at every depth.
A straight ray stays straight, and its parameter ``t'`` in [0, 1] is uniform in disparity,
so uniform samples in ``t'`` put as many near the camera as far away, where detail is visible.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from seenerf.render.rays import SceneBox

__all__ = ["FrustumSpace", "forward_facing_space", "frustum_box"]

MAX_VIEW_ANGLE_DEG = 25.0
"""A camera whose optical axis turns further than this from the mean one is not forward-facing."""

_MIN_FORWARD = 1e-6


@dataclass(frozen=True)
class FrustumSpace:
    """NDC of one reference camera.

    Attributes:
        w2c: ``(3, 4)`` world-to-camera of the reference camera, nested tuples.
        scale_x: ``2 fx / W``; ``scale_y`` ``2 fy / H`` (the image spans [-1, 1]).
        near: depth of the near plane in the reference camera; nothing closer is modelled.
    """

    w2c: tuple[tuple[float, ...], ...]
    scale_x: float
    scale_y: float
    near: float

    def rays(
        self, origins: torch.Tensor, directions: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """World rays ``(R, 3)`` as NDC rays, parameter 0 at the near plane, 1 at infinity.

        A ray that does not go forward in the reference camera never meets the scene: it is
        given an origin far beyond infinity (z' = 1e6) and no direction: it misses every box.
        """
        w2c = origins.new_tensor(self.w2c)
        o = origins @ w2c[:, :3].T + w2c[:, 3]
        d = directions @ w2c[:, :3].T
        backward = (d[:, 2] <= _MIN_FORWARD)[:, None]
        d = torch.cat([d[:, :2], d[:, 2:].clamp(min=_MIN_FORWARD)], dim=1)
        o = o + ((self.near - o[:, 2]) / d[:, 2])[:, None] * d
        ox, oy, oz = o.unbind(-1)
        dx, dy, dz = d.unbind(-1)
        ndc_origins = torch.stack(
            [self.scale_x * ox / oz, self.scale_y * oy / oz, 1.0 - 2.0 * self.near / oz], dim=-1
        )
        ndc_directions = torch.stack(
            [
                self.scale_x * (dx / dz - ox / oz),
                self.scale_y * (dy / dz - oy / oz),
                2.0 * self.near / oz,
            ],
            dim=-1,
        )
        beyond = ndc_origins.new_tensor([0.0, 0.0, 1e6])
        return (
            torch.where(backward, beyond, ndc_origins),
            torch.where(backward, torch.zeros_like(ndc_directions), ndc_directions),
        )

    def to_ndc(self, points: np.ndarray) -> np.ndarray:
        """World points ``(P, 3)`` in front of the near plane to NDC."""
        w2c = np.asarray(self.w2c)
        local = points @ w2c[:, :3].T + w2c[:, 3]
        z = np.maximum(local[:, 2], self.near)
        return np.stack(
            [self.scale_x * local[:, 0] / z, self.scale_y * local[:, 1] / z, 1 - 2 * self.near / z],
            axis=1,
        )

    def to_world(self, points: torch.Tensor) -> torch.Tensor:
        """NDC points ``(P, 3)`` (z' < 1) back to world points."""
        w2c = points.new_tensor(self.w2c)
        z = 2.0 * self.near / (1.0 - points[:, 2]).clamp(min=1e-6)
        local = torch.stack(
            [points[:, 0] * z / self.scale_x, points[:, 1] * z / self.scale_y, z], -1
        )
        return (local - w2c[:, 3]) @ w2c[:, :3]


def _mean_rotation(rotations: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(rotations.sum(axis=0))
    mean = u @ vt
    if np.linalg.det(mean) < 0:
        mean = u @ np.diag([1.0, 1.0, -1.0]) @ vt
    return mean


def forward_facing_space(
    c2w: np.ndarray, intrinsics: np.ndarray, bounds: np.ndarray, image_size: tuple[int, int]
) -> FrustumSpace | None:
    """The NDC of the mean training camera, or None when the cameras are not forward-facing.

    Forward-facing means every optical axis lies within :data:`MAX_VIEW_ANGLE_DEG` of the mean
    one and every camera centre lies well behind the near plane (at most half the near depth
    in front of the mean camera), so each training ray crosses the near plane going forward.

    Args:
        c2w: ``(..., 4, 4)`` camera-to-world poses, OpenCV axes.
        intrinsics: fx, fy, cx, cy.
        bounds: near and far scene depth.
        image_size: ``(height, width)``.
    """
    poses = np.asarray(c2w, np.float64).reshape(-1, 4, 4)
    rotation = _mean_rotation(poses[:, :3, :3])
    axes = poses[:, :3, 2]
    if np.degrees(np.arccos(np.clip(axes @ rotation[:, 2], -1, 1))).max() > MAX_VIEW_ANGLE_DEG:
        return None
    centre = poses[:, :3, 3].mean(axis=0)
    ahead = (poses[:, :3, 3] - centre) @ rotation[:, 2]
    near = 0.8 * float(bounds[0]) - max(float(ahead.max()), 0.0)
    if near <= 0.4 * float(bounds[0]):
        return None
    w2c = np.concatenate([rotation.T, -(rotation.T @ centre)[:, None]], axis=1)
    height, width = image_size
    return FrustumSpace(
        tuple(tuple(float(v) for v in row) for row in w2c),
        2.0 * float(intrinsics[0]) / width,
        2.0 * float(intrinsics[1]) / height,
        near,
    )


def frustum_box(
    space: FrustumSpace,
    c2w: np.ndarray,
    intrinsics: np.ndarray,
    bounds: np.ndarray,
    image_size: tuple[int, int],
) -> SceneBox:
    """Cube in NDC around every camera's view between the near plane and 1.5 x the far depth.

    Image corners and edge midpoints of every camera at a ladder of depths are mapped to NDC;
    the cube is padded by 5 % (what lies beyond ``z' = 1`` is never sampled: rays end there).
    """
    height, width = image_size
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    u = np.array([0, width / 2, width, 0, width, 0, width / 2, width], float)
    v = np.array([0, 0, 0, height / 2, height / 2, height, height, height], float)
    local = np.stack([(u - cx) / fx, (v - cy) / fy, np.ones_like(u)], axis=1)
    depths = np.geomspace(float(bounds[0]) * 0.8, float(bounds[1]) * 1.5, 8)
    poses = np.asarray(c2w, np.float64).reshape(-1, 4, 4)
    rays = np.einsum("pij,kj->pki", poses[:, :3, :3], local)
    world = poses[:, None, None, :3, 3] + depths[None, :, None, None] * rays[:, None]
    points = space.to_ndc(world.reshape(-1, 3))
    low, high = points.min(axis=0), points.max(axis=0)
    low[2] = -1.0
    half = 0.525 * (high - low).max()
    centre = (low + high) / 2
    return SceneBox(tuple(float(c) for c in centre - half), tuple(float(c) for c in centre + half))
