"""Event-based double integral (EDI): sharp latent frames from a blurry frame and its event bins.

A blurry frame is the exposure integral of the sharp frames inside it, which the trapezoid rule
writes as ``B = sum_k w_k L_k`` over the b+1 latent time points; between two latent time points
a pixel's log intensity changes by the threshold times its signed event count, so
``L_k = L_0 exp(theta C_k)`` with ``C_k`` the cumulative count up to point k. Solving for L_0
gives the weighted double-integral form ``L_0 = B / sum_k w_k exp(theta C_k)``.

The functions work per pixel, so a colour sensor's raw mosaic is handled as it is recorded:
every mosaic pixel gets its own event map (the DVS pixels carry the same colour filter), and the
latent mosaics are demosaiced afterwards, for COLMAP only.
"""

from __future__ import annotations

import numpy as np

from davis_io.errors import UsageError

__all__ = [
    "MAX_LOG_CHANGE",
    "cumulative_counts",
    "edi_latent_frames",
]

MAX_LOG_CHANGE = 12.0
"""Largest |theta C_k| applied, in natural-log units (a factor of about 1.6e5): hot pixels and
noise bursts cannot overflow ``exp`` or wipe out a frame."""


def cumulative_counts(counts: np.ndarray) -> np.ndarray:
    """Cumulative signed event counts at the b+1 latent time points.

    Args:
        counts: ``(b, H, W)`` signed (optionally calibrated) counts per bin.

    Returns:
        ``(b+1, H, W)`` float64 with ``C_0 = 0`` and ``C_k = sum_{j<k} counts_j``.
    """
    counts = np.asarray(counts, np.float64)
    if counts.ndim != 3:
        raise UsageError(f"event counts must be (b, H, W), got shape {counts.shape}")
    return np.concatenate([np.zeros((1, *counts.shape[1:])), np.cumsum(counts, axis=0)])


def _check_weights(weights: np.ndarray, points: int) -> np.ndarray:
    weights = np.asarray(weights, np.float64)
    if weights.shape != (points,):
        raise UsageError(f"expected {points} exposure weights (b+1), got shape {weights.shape}")
    if np.any(weights < 0) or not np.isclose(weights.sum(), 1.0, atol=1e-6):
        raise UsageError(
            f"exposure weights must be non-negative and sum to 1, got {np.round(weights, 4)}; "
            "recompute the bins of this session"
        )
    return weights


def _log_ratios(cumulative: np.ndarray, threshold: float) -> np.ndarray:
    return np.clip(threshold * cumulative, -MAX_LOG_CHANGE, MAX_LOG_CHANGE)


def edi_latent_frames(
    blurry: np.ndarray, counts: np.ndarray, weights: np.ndarray, threshold: float
) -> np.ndarray:
    """Sharp latent frames at the b+1 latent time points of one exposure.

    ``L_0 = B / (w_0 + sum_{k>=1} w_k exp(theta C_k))`` and ``L_k = L_0 exp(theta C_k)``, with
    the exponent clamped to ``±MAX_LOG_CHANGE``. The denominator is at least
    ``exp(-MAX_LOG_CHANGE)`` (weights are non-negative and sum to 1), so the result is finite
    for any finite input; a black pixel (``B = 0``) stays black and a clipped pixel gives the
    lower bound its clipped value implies.

    Args:
        blurry: ``(H, W)`` blurry frame, non-negative, in a domain proportional to irradiance
            (linearised values) or the normalised 8-bit image when no response curve is known.
        counts: ``(b, H, W)`` signed event counts per bin (calibrated counts preferred).
        weights: ``(b+1,)`` trapezoid weights of the exposure integral.
        threshold: contrast threshold theta in natural-log units per event, > 0.

    Returns:
        ``(b+1, H, W)`` float64 latent frames in the domain of ``blurry``. Their weighted sum
        equals ``blurry`` wherever no exponent was clamped.

    Raises:
        UsageError: shapes that do not fit together, bad weights or a non-positive threshold.
    """
    blurry = np.asarray(blurry, np.float64)
    cumulative = cumulative_counts(counts)
    weights = _check_weights(weights, len(cumulative))
    if cumulative.shape[1:] != blurry.shape:
        raise UsageError(
            f"event map {cumulative.shape[1:]} does not match the frame {blurry.shape}"
        )
    if not threshold > 0:
        raise UsageError(f"the contrast threshold must be > 0, got {threshold}")
    gains = np.exp(_log_ratios(cumulative, threshold))
    denominator = np.tensordot(weights, gains, axes=1)
    first = np.maximum(blurry, 0.0) / denominator
    return first[None] * gains
