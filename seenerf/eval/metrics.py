"""Image metrics: PSNR, SSIM, tone-mapped HDR and LDR scores, log contrast, residual blur."""

from __future__ import annotations

import math

import cv2
import numpy as np
import torch
import torch.nn.functional as F  # noqa: N812

__all__ = [
    "BLUR_SIGMAS_PX",
    "HDR_ALIGNMENTS",
    "align_channel_scale",
    "align_global_scale",
    "hdr_metrics",
    "ldr_metrics",
    "log_contrast",
    "psnr",
    "residual_blur",
    "ssim",
    "tone_map_pair",
]


def psnr(predicted: np.ndarray, truth: np.ndarray, data_range: float = 1.0) -> float:
    """Peak signal-to-noise ratio in dB; ``inf`` for identical images."""
    mse = float(np.mean((np.asarray(predicted, np.float64) - np.asarray(truth, np.float64)) ** 2))
    return math.inf if mse == 0 else 10.0 * math.log10(data_range**2 / mse)


def _gaussian_kernel(size: int = 11, sigma: float = 1.5) -> torch.Tensor:
    """The 1-D Gaussian whose outer product with itself is the SSIM window."""
    offsets = torch.arange(size, dtype=torch.float64) - (size - 1) / 2
    kernel = torch.exp(-(offsets**2) / (2 * sigma**2))
    return kernel / kernel.sum()


def ssim(predicted: np.ndarray, truth: np.ndarray, data_range: float = 1.0) -> float:
    """Structural similarity (Wang et al. 2004): Gaussian window 11, sigma 1.5, K1 0.01, K2 0.03.

    Args:
        predicted: ``(H, W)`` or ``(H, W, C)`` image.
        truth: reference image of the same shape.
        data_range: value range (1 for images in [0, 1]).

    Returns:
        Mean SSIM over the valid (unpadded) window positions and channels; images smaller than
        the window use the largest odd window that fits.

    The window is separable, so each local mean is two 1-D passes, the five maps in one call.
    """
    a = torch.as_tensor(np.asarray(predicted, np.float64))
    b = torch.as_tensor(np.asarray(truth, np.float64))
    if a.ndim == 2:
        a, b = a[..., None], b[..., None]
    a, b = a.permute(2, 0, 1)[:, None], b.permute(2, 0, 1)[:, None]
    size = min(11, a.shape[-2], a.shape[-1])
    kernel = _gaussian_kernel(size - (1 - size % 2))
    c1, c2 = (0.01 * data_range) ** 2, (0.03 * data_range) ** 2
    maps = torch.cat([a, b, a * a, b * b, a * b])
    local = F.conv2d(F.conv2d(maps, kernel.view(1, 1, -1, 1)), kernel.view(1, 1, 1, -1))
    mu_a, mu_b, mean_aa, mean_bb, mean_ab = local.chunk(5)
    var_a = mean_aa - mu_a**2
    var_b = mean_bb - mu_b**2
    cov = mean_ab - mu_a * mu_b
    index = ((2 * mu_a * mu_b + c1) * (2 * cov + c2)) / (
        (mu_a**2 + mu_b**2 + c1) * (var_a + var_b + c2)
    )
    return float(index.mean())


def align_channel_scale(predicted: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per-channel scale ``median(truth / predicted)``: radiance is known up to the CRF anchor.

    Args:
        predicted: ``(..., C)`` linear HDR.
        truth: reference HDR of the same shape.

    Returns:
        ``(C,)`` factors to multiply the prediction by.
    """
    pred = predicted.reshape(-1, predicted.shape[-1]).astype(np.float64)
    true = truth.reshape(-1, truth.shape[-1]).astype(np.float64)
    valid = (pred > 1e-12) & (true > 0)
    ratios = [
        np.median(true[valid[:, c], c] / pred[valid[:, c], c]) if valid[:, c].any() else 1.0
        for c in range(pred.shape[1])
    ]
    return np.asarray(ratios)


def align_global_scale(predicted: np.ndarray, truth: np.ndarray) -> float:
    """One scale ``median(truth / predicted)`` over every pixel and channel.

    Radiance is known up to the CRF anchor's scale, one number; a colour cast stays.
    """
    pred = np.asarray(predicted, np.float64).ravel()
    true = np.asarray(truth, np.float64).ravel()
    valid = (pred > 1e-12) & (true > 0)
    return float(np.median(true[valid] / pred[valid])) if valid.any() else 1.0


def tone_map_pair(predicted: np.ndarray, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The open HDR protocol's tone map of a prediction and its truth.

    Both are divided by the truth's maximum, the prediction is clipped to [0, 1], then
    ``ln(1 + 5000 x) / ln(5001)`` is applied.
    """
    scale = float(truth.max()) if truth.max() > 0 else 1.0
    pred = np.clip(predicted / scale, 0.0, 1.0)
    true = np.clip(truth / scale, 0.0, None)
    tone = math.log(5001.0)
    return np.log1p(5000.0 * pred) / tone, np.log1p(5000.0 * true) / tone


HDR_ALIGNMENTS = {
    "global": align_global_scale,
    "channel": align_channel_scale,
    "none": lambda predicted, truth: 1.0,
}
"""How HDR views are scaled onto the truth before scoring: one scale (the protocol), one per
colour channel (which erases colour casts: an extra column), or none."""


def hdr_metrics(
    predicted: list[np.ndarray], truth: list[np.ndarray], align: str, structural: bool = True
) -> dict:
    """Mean tone-mapped PSNR and SSIM over views after scaling them onto the truth.

    Args:
        predicted: linear HDR views ``(H, W, C)``.
        truth: reference views of the same shapes.
        align: a key of :data:`HDR_ALIGNMENTS`, fitted over all views at once.
        structural: compute SSIM (else NaN).
    """
    if not predicted:
        return {"psnr": math.nan, "ssim": math.nan, "views": 0}
    scale = HDR_ALIGNMENTS[align](np.stack(predicted), np.stack(truth))
    pairs = [tone_map_pair(p * scale, t) for p, t in zip(predicted, truth, strict=True)]
    return {
        "psnr": float(np.mean([psnr(p, t) for p, t in pairs])),
        "ssim": float(np.mean([ssim(p, t) for p, t in pairs])) if structural else math.nan,
        "views": len(pairs),
        "scale": np.atleast_1d(scale).tolist(),
    }


def log_contrast(predicted: np.ndarray, truth: np.ndarray) -> list[float]:
    """Per channel, the slope of ln(predicted) against ln(truth): 1 when contrast is right.

    A single exposure leaves the field's log contrast free (the learned CRF can stretch to
    match any), and only the events pin it; a slope under 1 means contrast was compressed, which
    brightens shadows at long exposures. Fitted by least squares over the pixels whose truth
    lies between its 5th and 99th percentile (away from black and clipped highlights).

    Args:
        predicted: linear HDR ``(..., C)``, positive.
        truth: reference of the same shape.
    """
    channels = np.asarray(truth).shape[-1]
    log_predicted = np.log(np.maximum(np.asarray(predicted, np.float64), 1e-12))
    log_truth = np.log(np.maximum(np.asarray(truth, np.float64), 1e-12))
    slopes = []
    for c in range(channels):
        x, y = log_truth[..., c].ravel(), log_predicted[..., c].ravel()
        low, high = np.quantile(x, [0.05, 0.99])
        keep = (x > low) & (x < high)
        x, y = x[keep] - x[keep].mean(), y[keep] - y[keep].mean()
        slopes.append(float((x @ y) / max(float(x @ x), 1e-12)))
    return slopes


BLUR_SIGMAS_PX = tuple(np.arange(0.0, 2.01, 0.125))
"""Gaussian blurs of the truth tried by :func:`residual_blur`, pixels (standard deviation)."""


def _gaussian_blur(image: np.ndarray, sigma: float) -> np.ndarray:
    """``image`` ``(H, W, C)`` blurred per channel (unchanged for ``sigma`` 0)."""
    if sigma <= 0:
        return image
    return cv2.GaussianBlur(image, (0, 0), sigma).reshape(image.shape)


def residual_blur(predicted: list[np.ndarray], truth: list[np.ndarray]) -> dict:
    """How blurred the renders are: the Gaussian blur of the truth they match best.

    Each truth view is blurred by each of :data:`BLUR_SIGMAS_PX` and compared with the render by
    PSNR. A field as sharp as the truth matches it unblurred (0 px); a grid field cannot be
    sharper than its texels, so even one trained on sharp truth matches a blur of a fraction of
    a texel.

    Args:
        predicted: LDR views ``(H, W, C)`` in [0, 1].
        truth: reference views of the same shapes.

    Returns:
        ``sigma_px``: the best-matching blur (Gaussian standard deviation, pixels);
        ``psnr_gain``: PSNR there minus PSNR against the unblurred truth, dB.
    """
    scores = [
        np.mean(
            [
                psnr(np.clip(p, 0, 1), _gaussian_blur(t, sigma))
                for p, t in zip(predicted, truth, strict=True)
            ]
        )
        for sigma in BLUR_SIGMAS_PX
    ]
    best = int(np.argmax(scores))
    gain = float(scores[best] - scores[0]) if best else 0.0  # PSNR is infinite on a perfect match
    return {"sigma_px": float(BLUR_SIGMAS_PX[best]), "psnr_gain": gain}


def ldr_metrics(
    predicted: list[np.ndarray], truth: list[np.ndarray], structural: bool = True
) -> dict:
    """Mean PSNR and SSIM (NaN unless ``structural``) of LDR images in [0, 1]."""
    if not predicted:
        return {"psnr": math.nan, "ssim": math.nan, "views": 0}
    pairs = [(np.clip(p, 0, 1), t) for p, t in zip(predicted, truth, strict=True)]
    return {
        "psnr": float(np.mean([psnr(p, t) for p, t in pairs])),
        "ssim": float(np.mean([ssim(p, t) for p, t in pairs])) if structural else math.nan,
        "views": len(predicted),
    }
