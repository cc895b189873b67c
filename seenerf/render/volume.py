"""Volume rendering of packed samples: weights from densities, then per-ray weighted sums."""

from __future__ import annotations

import torch

__all__ = ["MAX_OPTICAL_DEPTH", "composite", "sample_weights"]

MAX_OPTICAL_DEPTH = 30.0
"""Optical depth per sample is capped here (exp(-30) ~ 1e-13): opaque, and never inf."""


def sample_weights(
    density: torch.Tensor,
    delta: torch.Tensor,
    ray_index: torch.Tensor,
    num_rays: int,
    per_ray: int = 0,
) -> tuple[torch.Tensor, torch.Tensor]:
    """Blending weights ``T_i (1 - exp(-sigma_i delta_i))`` of samples packed ray after ray.

    Args:
        density: ``(S,)`` non-negative density per box unit.
        delta: ``(S,)`` sample interval lengths in box units.
        ray_index: ``(S,)`` int64 ray of each sample, non-decreasing.
        num_rays: R.
        per_ray: samples of every ray when all rays have the same count (``S == R * per_ray``);
            0 for a ragged packing. The equal-count case takes a per-row cumulative sum.

    Returns:
        ``weights`` ``(S,)`` and ``opacity`` ``(R,)`` = sum of the weights of each ray (0 for a
        ray without samples).
    """
    optical = (density * delta).clamp(0.0, MAX_OPTICAL_DEPTH)
    if per_ray > 0 and optical.numel() == num_rays * per_ray:
        rows = optical.reshape(num_rays, per_ray)
        before = torch.cumsum(rows, dim=1) - rows
        weights = (torch.exp(-before) * (1.0 - torch.exp(-rows))).reshape(-1)
        return weights, weights.reshape(num_rays, per_ray).sum(dim=1)
    # Transmittance from an exclusive cumulative sum per ray, accumulated in float64 so that
    # long packed batches do not lose the small per-ray differences.
    running = torch.cumsum(optical.double(), dim=0)
    per_ray_sum = torch.zeros(num_rays, dtype=torch.float64, device=density.device)
    per_ray_sum.index_add_(0, ray_index, optical.double())
    ray_offset = torch.cumsum(per_ray_sum, dim=0) - per_ray_sum
    before = (running - optical.double() - ray_offset[ray_index]).clamp(min=0.0).float()
    weights = torch.exp(-before) * (1.0 - torch.exp(-optical))
    opacity = torch.zeros(num_rays, dtype=weights.dtype, device=weights.device)
    opacity.index_add_(0, ray_index, weights)
    return weights, opacity


def composite(
    weights: torch.Tensor,
    values: torch.Tensor,
    ray_index: torch.Tensor,
    opacity: torch.Tensor,
    background: torch.Tensor,
) -> torch.Tensor:
    """Per-ray ``sum_i w_i values_i + (1 - opacity) background``.

    Args:
        weights: ``(S,)`` from :func:`sample_weights`.
        values: ``(S, C)`` per-sample values (log radiance, or LDR for a 3-D point CRF).
        ray_index: ``(S,)`` ray of each sample.
        opacity: ``(R,)`` accumulated weight per ray.
        background: ``(C,)`` value seen where the ray leaves the scene unoccluded.

    Returns:
        ``(R, C)``; a ray that hits nothing returns ``background``.
    """
    out = torch.zeros(opacity.shape[0], values.shape[-1], dtype=values.dtype, device=values.device)
    out.index_add_(0, ray_index, weights[:, None] * values)
    return out + (1.0 - opacity).clamp(min=0.0)[:, None] * background
