"""Sub-frames of the exposure integral: more poses than the b+1 latent ones where the camera moved.

The blur model (eq. 6) sums radiance at the b+1 latent poses with trapezoid weights. When the
image moves several pixels between two latent poses, that sum is a few ghosts of a sharp image,
not the smear the sensor integrated, and the field learns to blur itself to match. Splitting
each bin into ``m`` sub-frames (poses interpolated between its two latent poses: rotation
slerped, centre linear) samples the smear ``m`` times finer. The events keep their b bins (every
``m``-th pose is a latent pose), but the event model follows each pixel through the sub-frames,
so a pixel whose dead time an edge outruns is owed its events from when the edge crossed it.
Each sub-frame renders every pixel of a batch once more (3 per bin: about 2.5x fewer steps in a
budget), so a fit uses ``m = 1`` unless told otherwise.
"""

from __future__ import annotations

import numpy as np

from davis_io.geometry import interpolate_poses
from davis_io.session import subdivide, trapezoid_weights
from seenerf.data.arrays import TrainingData

__all__ = [
    "latent_fractions",
    "latent_travel_px",
    "median_travel_px",
    "refine_exposure",
]

_TIME_UNITS = 1_000_000
"""Exposure fractions are handed to the trapezoid weights in millionths."""


def latent_fractions(weights: np.ndarray) -> np.ndarray:
    """Time of each latent point as a fraction of the exposure, from its trapezoid weights.

    Trapezoid weights are ``w_i = (t_{i+1} - t_{i-1}) / 2T`` (ends repeated), so the intervals
    follow one after the other: ``d_0 = 2 w_0``, ``d_k = 2 w_k - d_{k-1}``. A row that is not the
    trapezoid weights of any times (the even weights of a zero-length window) gets evenly spaced
    points.

    Args:
        weights: ``(F, b+1)`` trapezoid weights, each row summing to 1.

    Returns:
        ``(F, b+1)`` non-decreasing fractions from 0 to 1.
    """
    weights = np.asarray(weights, np.float64)
    frames, points = weights.shape
    intervals = np.empty((frames, points - 1))
    previous = np.zeros(frames)
    for k in range(points - 1):
        previous = 2.0 * weights[:, k] - previous
        intervals[:, k] = previous
    consistent = np.all(intervals >= -1e-6, axis=1) & (np.abs(intervals.sum(axis=1) - 1) < 1e-3)
    intervals[~consistent] = 1.0 / max(points - 1, 1)
    intervals = intervals.clip(0.0, None)
    intervals /= intervals.sum(axis=1, keepdims=True)
    return np.concatenate([np.zeros((frames, 1)), np.cumsum(intervals, axis=1)], axis=1).clip(0, 1)


def refine_exposure(
    c2w: np.ndarray, weights: np.ndarray, subdivisions: int
) -> tuple[np.ndarray, np.ndarray]:
    """Poses and trapezoid weights of each exposure with every bin split into sub-frames.

    Sub-frame j of bin k lies at fraction j/m of the bin's time and of the way from latent pose
    k to latent pose k+1, so a bin that lasted no time keeps its poses and gets no weight.

    Args:
        c2w: ``(F, b+1, 4, 4)`` latent poses.
        weights: ``(F, b+1)`` their trapezoid weights.
        subdivisions: sub-frames per bin m (1 returns the inputs).

    Returns:
        ``(F, b m + 1, 4, 4)`` poses and ``(F, b m + 1)`` weights summing to 1 per frame;
        pose ``k m`` is latent pose ``k``.
    """
    if subdivisions == 1:
        return c2w, weights
    fractions = latent_fractions(weights)
    frames, points = fractions.shape
    fine_c2w = np.empty((frames, (points - 1) * subdivisions + 1, 4, 4), c2w.dtype)
    fine_weights = np.empty(fine_c2w.shape[:2], weights.dtype)
    for frame in range(frames):
        fine = subdivide(fractions[frame], subdivisions)
        fine_weights[frame] = trapezoid_weights(np.round(fine * _TIME_UNITS).astype(np.int64))
        for k in range(points - 1):
            fine_c2w[frame, k * subdivisions : (k + 1) * subdivisions] = interpolate_poses(
                np.array([0, subdivisions]), c2w[frame, k : k + 2], np.arange(subdivisions)
            )
        fine_c2w[frame, ::subdivisions] = c2w[frame]
    return fine_c2w, fine_weights


def latent_travel_px(
    c2w: np.ndarray, intrinsics: np.ndarray, depth: float, image_size: tuple[int, int]
) -> np.ndarray:
    """Largest image motion between neighbouring latent poses of each frame, pixels.

    A 5x5 grid of pixels is lifted to ``depth`` from each latent pose and projected into the
    next one.

    Args:
        c2w: ``(F, P, 4, 4)`` latent poses, OpenCV axes.
        intrinsics: fx, fy, cx, cy.
        depth: scene depth along the optical axis the motion is measured at.
        image_size: ``(height, width)``.

    Returns:
        ``(F,)`` pixels.
    """
    fx, fy, cx, cy = (float(value) for value in intrinsics)
    height, width = image_size
    v, u = np.meshgrid(np.linspace(0, height - 1, 5), np.linspace(0, width - 1, 5), indexing="ij")
    local = np.stack([(u - cx) / fx * depth, (v - cy) / fy * depth, np.full_like(u, depth)], -1)
    local = local.reshape(-1, 3)
    poses = np.asarray(c2w, np.float64)
    world = np.einsum("fpij,nj->fpni", poses[:, :-1, :3, :3], local) + poses[:, :-1, None, :3, 3]
    w2c_rotation = np.swapaxes(poses[:, 1:, :3, :3], -1, -2)
    seen = np.einsum("fpij,fpnj->fpni", w2c_rotation, world - poses[:, 1:, None, :3, 3])
    z = np.clip(seen[..., 2], 1e-6, None)
    column = fx * seen[..., 0] / z + cx - u.ravel()
    row = fy * seen[..., 1] / z + cy - v.ravel()
    return np.hypot(column, row).max(axis=(1, 2))


def median_travel_px(data: TrainingData) -> float:
    """Median over frames of :func:`latent_travel_px` at the scene's mean depth.

    The depth is the harmonic mean of the near and far bounds: parallax goes with inverse depth.
    """
    near, far = (float(value) for value in data.bounds)
    depth = 2.0 / (1.0 / near + 1.0 / far)
    travel = latent_travel_px(data.c2w, data.intrinsics, depth, data.image_size)
    return float(np.median(travel))
