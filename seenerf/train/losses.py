"""Training losses: LDR (eq. 13), events (eq. 14) and the oracle's HDR loss.

A method (:mod:`seenerf.train.methods`) weighs and sums them (eq. 15).
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F

__all__ = [
    "NOISE_REFERENCE",
    "SPAN_ROBUST",
    "event_loss",
    "exposure_loss",
    "hdr_tone_map",
    "ldr_loss",
    "noise_even",
    "sharp_hdr_loss",
    "span_loss",
    "tone_mapped_render",
]

SPAN_ROBUST = 1.0
"""Thresholds beyond which a span's error counts linearly. The events of many frames carry
errors of several thresholds against the light (on the emulator's recordings 2.6-4.6 thresholds
RMS over 1-8 frames, its pixels slow in the dark; 0.5-1.1 on a camera of ideal pixels): squared,
they outweighed the frames and cost 1.2 dB HDR on `corridor`, counted linearly beyond one
threshold 0.1 dB."""

NOISE_REFERENCE = 0.25
"""Value above black where :func:`noise_even` keeps the plain squared error's weight."""


def ldr_loss(predicted: torch.Tensor, recorded: torch.Tensor) -> torch.Tensor:
    """Mean squared error of predicted and recorded LDR values (eq. 13, mean instead of sum)."""
    return (predicted - recorded).square().mean()


def noise_even(values: torch.Tensor, black: float, offset: float) -> torch.Tensor:
    """Linear frame values on a scale where their noise is the same at every level.

    A raw value's variance grows with its light, ``gain * (v - black) + floor``: squared errors
    of plain values let the bright pixels' noise drown the dark pixels' signal, and a field
    can then be brighter than the frames in the shadows at little cost. On the scale
    ``2 sqrt(r + o) sqrt(v - black + o)`` (``o = floor / gain``, ``r`` the
    :data:`NOISE_REFERENCE`; Anscombe's transform of Poisson counts, shifted for the read noise)
    the variance is the same everywhere and a squared error weighs each pixel by the inverse of
    its noise; at ``v - black = r`` the scale's slope is 1, as the plain error's.
    """
    above = (values - black).clamp(min=0.0) + offset
    return 2 * math.sqrt(NOISE_REFERENCE + offset) * torch.sqrt(above)


def event_loss(
    predicted: torch.Tensor,
    measured: torch.Tensor,
    settled: torch.Tensor,
    weights: torch.Tensor | None = None,
) -> torch.Tensor:
    """Squared count error over the spans between a pixel's settled latent points (eq. 14).

    A pixel that was still firing at its dead-time limit at a bin's end had not fired all it
    owed, so its count of that bin falls short and the next one's holds the rest: the bins on
    either side are compared as one span, whose count is whole. Spans that start or end where
    the pixel was not settled (the exposure's first or last point) are left out. With every
    point settled this is the mean over pixels and bins of each bin's squared error.

    Args:
        predicted: ``(R, b)`` predicted counts.
        measured: ``(R, b)`` recorded counts.
        settled: ``(R, b+1)`` bool, whether each pixel was settled at each latent point.
        weights: ``(R,)`` each pixel's weight on its spans' squared errors (None: all 1).

    Returns:
        The weighted sum of the spans' squared errors over ``R * b``; zero for an empty batch.
    """
    if predicted.numel() == 0:
        return predicted.new_zeros(())
    residual = torch.cumsum(predicted - measured, dim=1)
    at_last = torch.zeros_like(residual[:, 0])
    started = settled[:, 0]
    total = torch.zeros_like(at_last)
    for point in range(1, settled.shape[1]):
        here = residual[:, point - 1]
        ends = started & settled[:, point]
        total = total + torch.where(ends, here - at_last, 0.0).square()
        at_last = torch.where(settled[:, point], here, at_last)
        started = started | settled[:, point]
    return _weighted_sum(total, weights) / predicted.numel()


def exposure_loss(
    predicted: torch.Tensor,
    measured: torch.Tensor,
    settled: torch.Tensor,
    lone: torch.Tensor,
    weights: torch.Tensor | None = None,
) -> torch.Tensor:
    """Squared count error of each lone pixel's whole exposure, first latent point to last.

    The exposure is one span of :func:`event_loss`: pixels not settled at its first or last
    point are left out, and the sum is over ``R * b`` as that loss's.

    Args:
        predicted: ``(R, b)`` predicted counts.
        measured: ``(R, b)`` recorded counts.
        settled: ``(R, b+1)`` bool, whether each pixel was settled at each latent point.
        lone: ``(R,)`` bool, the pixels compared over their whole exposure.
        weights: ``(R,)`` each pixel's weight on its squared error (None: all 1).

    Returns:
        The weighted sum of the exposures' squared errors over ``R * b``; zero for an empty
        batch.
    """
    if predicted.numel() == 0:
        return predicted.new_zeros(())
    whole = lone & settled[:, 0] & settled[:, -1]
    error = (predicted - measured).sum(dim=1)
    return _weighted_sum(torch.where(whole, error, 0.0).square(), weights) / predicted.numel()


def _weighted_sum(values: torch.Tensor, weights: torch.Tensor | None) -> torch.Tensor:
    """The sum of ``values``, each times its weight where weights are given."""
    return values.sum() if weights is None else torch.dot(values, weights)


def span_loss(
    predicted: torch.Tensor,
    measured: torch.Tensor,
    known: torch.Tensor,
    weights: torch.Tensor | None = None,
) -> torch.Tensor:
    """Robust mean error of the spans' changes, in thresholds, over the spans of known change.

    A span's error counts as its square within :data:`SPAN_ROBUST` thresholds and grows linearly
    beyond (Huber's loss, doubled), times its weight; zero where no span's change is known.

    Args:
        predicted: ``(R,)`` predicted changes.
        measured: ``(R,)`` the recorded ones.
        known: ``(R,)`` bool, the spans whose change is whole.
        weights: ``(R,)`` each span's weight on its error (None: all 1).
    """
    residual = torch.where(known, predicted - measured, 0.0)
    error = F.huber_loss(residual, torch.zeros_like(residual), reduction="none", delta=SPAN_ROBUST)
    if weights is not None:
        error = error * weights
    return 2 * error.sum() / known.sum().clamp(min=1)


def hdr_tone_map(hdr: torch.Tensor, scale: torch.Tensor | float) -> torch.Tensor:
    """Open HDR tone map ``ln(1 + 5000 x) / ln(5001)`` of ``x = hdr / scale`` (x >= 0)."""
    return torch.log1p(5000.0 * (hdr / scale).clamp(min=0.0)) / math.log(5001.0)


def tone_mapped_render(log_radiance: torch.Tensor, scale: torch.Tensor | float) -> torch.Tensor:
    """:func:`hdr_tone_map` of rendered log radiance (clamped where ``exp`` would overflow)."""
    return hdr_tone_map(torch.exp(log_radiance.clamp(max=60.0)), scale)


def sharp_hdr_loss(
    log_radiance: torch.Tensor, truth_hdr: torch.Tensor, scale: float
) -> torch.Tensor:
    """MSE of tone-mapped rendered and true sharp HDR (the oracle's supervision)."""
    predicted = tone_mapped_render(log_radiance, scale)
    return (predicted - hdr_tone_map(truth_hdr, scale)).square().mean()
