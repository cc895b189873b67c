"""Camera rays in OpenCV axes and the axis-aligned box that holds the scene."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

__all__ = ["SceneBox", "camera_rays", "in_any_view", "intersect_box", "scene_box_from_cameras"]


@dataclass(frozen=True)
class SceneBox:
    """Axis-aligned box of the scene in world units; fields see it as ``[-1, 1]^3``.

    Attributes:
        low: ``(3,)`` minimum corner.
        high: ``(3,)`` maximum corner.
    """

    low: tuple[float, float, float]
    high: tuple[float, float, float]

    def normalise(self, points: torch.Tensor) -> torch.Tensor:
        """Map world points ``(..., 3)`` to box coordinates in ``[-1, 1]``."""
        low = points.new_tensor(self.low)
        high = points.new_tensor(self.high)
        return (points - low) / (high - low) * 2.0 - 1.0

    def to_world(self, points: torch.Tensor) -> torch.Tensor:
        """Inverse of :meth:`normalise`: box coordinates ``(..., 3)`` to world points."""
        low = points.new_tensor(self.low)
        high = points.new_tensor(self.high)
        return (points + 1.0) * 0.5 * (high - low) + low

    @property
    def size(self) -> float:
        """Longest side of the box, world units."""
        return float(max(h - lo for h, lo in zip(self.high, self.low, strict=True)))


def scene_box_from_cameras(
    c2w: np.ndarray, intrinsics: np.ndarray, bounds: np.ndarray, image_size: tuple[int, int]
) -> SceneBox:
    """Cube around every camera's view frustum between the near and far depth, padded by 5 %.

    A cube keeps box units isotropic, so densities and distances mean the same along every axis.

    Args:
        c2w: ``(..., 4, 4)`` camera-to-world poses, OpenCV axes.
        intrinsics: fx, fy, cx, cy in pixels.
        bounds: near, far depth.
        image_size: ``(height, width)``.
    """
    height, width = image_size
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    corners = np.array([[0, 0], [width, 0], [0, height], [width, height]], float)
    directions = np.stack(
        [(corners[:, 0] - cx) / fx, (corners[:, 1] - cy) / fy, np.ones(4)], axis=1
    )
    depths = np.array([bounds[0], bounds[1]], float)
    local = (directions[None] * depths[:, None, None]).reshape(-1, 3)
    poses = np.asarray(c2w, float).reshape(-1, 4, 4)
    world = np.einsum("pij,kj->pki", poses[:, :3, :3], local) + poses[:, None, :3, 3]
    points = np.concatenate([world.reshape(-1, 3), poses[:, :3, 3]])
    low, high = points.min(axis=0), points.max(axis=0)
    half = 0.55 * (high - low).max()
    centre = (low + high) / 2
    return SceneBox(tuple(float(v) for v in centre - half), tuple(float(v) for v in centre + half))


UNDISTORT_ITERATIONS = 20
"""Fixed-point steps that invert the lens model: within 1e-6 px of OpenCV's answer at the
corners of a DAVIS346 behind a strongly barrel-distorting lens (k1 = -0.35)."""


def undistorted(
    x: torch.Tensor, y: torch.Tensor, distortion: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """Undistorted normalised coordinates of distorted ones, under OpenCV's lens model.

    The model maps ``(x, y)`` to ``(x r + dx, y r + dy)`` with the radial factor
    ``r = (1 + k1 s + k2 s^2 + k3 s^3) / (1 + k4 s + k5 s^2 + k6 s^3)`` of ``s = x^2 + y^2``
    and the tangential terms ``dx = 2 p1 x y + p2 (s + 2 x^2)``,
    ``dy = p1 (s + 2 y^2) + 2 p2 x y``; it is inverted by fixed-point iteration.

    Args:
        x: ``(R,)`` distorted ``(u - cx) / fx``.
        y: ``(R,)`` distorted ``(v - cy) / fy``.
        distortion: OpenCV's ``k1, k2, p1, p2[, k3[, k4, k5, k6]]`` (empty: no distortion).
    """
    k1, k2, p1, p2, k3, k4, k5, k6 = torch.nn.functional.pad(
        distortion.to(x.dtype), (0, 8 - distortion.numel())
    ).unbind()
    xu, yu = x, y
    for _ in range(UNDISTORT_ITERATIONS):
        s = xu * xu + yu * yu
        radial = (1 + s * (k1 + s * (k2 + s * k3))) / (1 + s * (k4 + s * (k5 + s * k6)))
        dx = 2 * p1 * xu * yu + p2 * (s + 2 * xu * xu)
        dy = p1 * (s + 2 * yu * yu) + 2 * p2 * xu * yu
        xu, yu = (x - dx) / radial, (y - dy) / radial
    return xu, yu


def camera_rays(
    c2w: torch.Tensor,
    intrinsics: torch.Tensor,
    u: torch.Tensor,
    v: torch.Tensor,
    distortion: torch.Tensor | None = None,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Rays through pixel centres; the ray parameter is the depth along the optical axis.

    Args:
        c2w: ``(R, 4, 4)`` camera-to-world of each ray (or ``(4, 4)`` for all).
        intrinsics: ``(4,)`` fx, fy, cx, cy in pixels; pixel (u, v) has its centre at (u, v).
        u: ``(R,)`` column index.
        v: ``(R,)`` row index.
        distortion: the lens's OpenCV coefficients (:func:`undistorted`), or None (or empty)
            for a pinhole.

    Returns:
        ``origins`` and ``directions``, each ``(R, 3)``; ``directions`` has camera z = 1.
    """
    x, y = normalised_coordinates(intrinsics, u, v, distortion)
    return rays_through(c2w, x, y)


def normalised_coordinates(
    intrinsics: torch.Tensor,
    u: torch.Tensor,
    v: torch.Tensor,
    distortion: torch.Tensor | None = None,
) -> tuple[torch.Tensor, torch.Tensor]:
    """``x / z`` and ``y / z`` of the rays through pixels ``(u, v)`` (see :func:`camera_rays`)."""
    fx, fy, cx, cy = intrinsics.unbind(-1)
    x, y = (u - cx) / fx, (v - cy) / fy
    if distortion is not None and distortion.numel():
        x, y = undistorted(x, y, distortion)
    return x, y


def pixel_coordinates(
    intrinsics: torch.Tensor, image_size: tuple[int, int], distortion: torch.Tensor | None = None
) -> tuple[torch.Tensor, torch.Tensor]:
    """``x / z`` and ``y / z`` of every pixel's ray, ``(H * W,)`` each, row by row."""
    height, width = image_size
    rows, columns = torch.meshgrid(
        torch.arange(height, device=intrinsics.device),
        torch.arange(width, device=intrinsics.device),
        indexing="ij",
    )
    u, v = columns.reshape(-1).float(), rows.reshape(-1).float()
    return normalised_coordinates(intrinsics, u, v, distortion)


def rays_through(
    c2w: torch.Tensor, x: torch.Tensor, y: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """Origins and directions (camera z = 1) of the rays of normalised ``(x, y)``.

    Args:
        c2w: ``(R, 4, 4)`` camera-to-world of each ray (or ``(4, 4)`` for all).
        x: ``(R,)`` ``x / z`` in the camera's frame.
        y: ``(R,)`` ``y / z``.
    """
    local = torch.stack([x, y, torch.ones_like(x)], dim=-1)
    rotation = c2w[..., :3, :3]
    directions = (rotation @ local.unsqueeze(-1)).squeeze(-1)
    origins = c2w[..., :3, 3].expand_as(directions)
    return origins, directions


def intersect_box(
    origins: torch.Tensor, directions: torch.Tensor, box: SceneBox, near: float, far: float
) -> tuple[torch.Tensor, torch.Tensor]:
    """Entry and exit ray parameters of the box, limited to ``[near, far]``.

    A ray that misses the box gets ``t_exit == t_entry`` (an empty interval), never NaN.

    Returns:
        ``t_entry`` and ``t_exit``, each ``(R,)``.
    """
    low = origins.new_tensor(box.low)
    high = origins.new_tensor(box.high)
    safe = torch.where(directions.abs() < 1e-9, torch.full_like(directions, 1e-9), directions)
    t_low = (low - origins) / safe
    t_high = (high - origins) / safe
    t_entry = torch.minimum(t_low, t_high).amax(dim=-1).clamp(min=near)
    t_exit = torch.maximum(t_low, t_high).amin(dim=-1).clamp(max=far)
    return t_entry, torch.maximum(t_exit, t_entry)


def in_any_view(
    points: np.ndarray,
    c2w: np.ndarray,
    intrinsics: np.ndarray,
    bounds: np.ndarray,
    image_size: tuple[int, int],
    margin_px: float = 8.0,
) -> np.ndarray:
    """Which world points ``(P, 3)`` project inside some camera's image between near and far.

    Args:
        points: world points.
        c2w: ``(..., 4, 4)`` cameras, OpenCV axes.
        intrinsics: fx, fy, cx, cy.
        bounds: near, far depth.
        image_size: ``(height, width)``.
        margin_px: tolerance around the image border, pixels.

    Returns:
        ``(P,)`` bool.
    """
    height, width = image_size
    fx, fy, cx, cy = (float(v) for v in intrinsics)
    seen = np.zeros(len(points), bool)
    for pose in np.asarray(c2w, np.float64).reshape(-1, 4, 4):
        local = (points - pose[:3, 3]) @ pose[:3, :3]
        depth = local[:, 2]
        safe = np.where(depth > 1e-9, depth, 1e-9)
        u, v = fx * local[:, 0] / safe + cx, fy * local[:, 1] / safe + cy
        seen |= (
            (depth >= bounds[0])
            & (depth <= bounds[1])
            & (u > -margin_px)
            & (u < width + margin_px)
            & (v > -margin_px)
            & (v < height + margin_px)
        )
    return seen
