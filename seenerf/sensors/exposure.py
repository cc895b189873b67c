"""The exposure integral (eq. 6): a blurry pixel is a weighted sum of radiance at b+1 poses."""

from __future__ import annotations

import torch
from torch import nn

__all__ = ["ExposureIntegral", "blur_log_radiance"]

_TINY_WEIGHT = 1e-12


def blur_log_radiance(log_radiance: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """``ln(sum_i w_i exp(logE_i))``, computed with logsumexp so no radiance under- or overflows.

    Args:
        log_radiance: ``(R, P, C)`` natural-log linear radiance at P = b+1 latent poses.
        weights: ``(R, P)`` trapezoid weights (sum 1 per row; zero weights are allowed).

    Returns:
        ``(R, C)`` log of the time-averaged radiance.
    """
    log_weights = torch.log(weights.clamp(min=_TINY_WEIGHT))[..., None]
    return torch.logsumexp(log_radiance + log_weights, dim=1)


class ExposureIntegral(nn.Module):
    """Module form of :func:`blur_log_radiance` (no parameters)."""

    def forward(self, log_radiance: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
        """See :func:`blur_log_radiance`."""
        return blur_log_radiance(log_radiance, weights)
