"""Scores of rendered views against the truth, and their one-line-per-score printout."""

from __future__ import annotations

import numpy as np

from seenerf.data.arrays import TrainingData
from seenerf.eval.metrics import hdr_metrics, ldr_metrics, log_contrast, residual_blur
from seenerf.eval.perceptual import lpips_scorer
from seenerf.eval.views import RenderedViews

__all__ = ["format_scores", "score_views"]


def score_views(views: RenderedViews, data: TrainingData, *, psnr_only: bool = False) -> dict:
    """PSNR / SSIM of HDR (tone-mapped after one scale; per-channel and raw beside) and of LDR.

    The novel-exposure score is the mean over the bracket's second and fourth exposures (the
    paper's protocol). ``residual_blur`` measures how sharp the views at the bracket's middle
    exposure are. LPIPS is added per exposure only when its weights are on this machine;
    ``lpips`` says which. With ``psnr_only`` the HDR (one scale), LDR and novel-exposure PSNRs
    alone, the SSIMs NaN: a second look at the same views from other poses.
    """
    test = data.test
    truth_hdr = list(test.hdr)
    structural = not psnr_only
    scores = {"hdr": hdr_metrics(views.hdr, truth_hdr, "global", structural), "ldr": {}}
    for index, exposure in enumerate(views.exposures_s):
        truth_ldr = list(test.ldr[:, index])
        scores["ldr"][f"{exposure:g}"] = ldr_metrics(views.ldr[index], truth_ldr, structural)
    novel = [
        scores["ldr"][f"{views.exposures_s[i]:g}"] for i in (1, 3) if i < len(views.exposures_s)
    ]
    scores["novel_exposure"] = {
        "psnr": float(np.mean([m["psnr"] for m in novel])) if novel else float("nan"),
        "ssim": float(np.mean([m["ssim"] for m in novel])) if novel else float("nan"),
    }
    if psnr_only:
        return scores
    scores["hdr_per_channel"] = hdr_metrics(views.hdr, truth_hdr, align="channel")
    scores["hdr_unaligned"] = hdr_metrics(views.hdr, truth_hdr, align="none")
    scores["log_contrast"] = log_contrast(np.stack(views.hdr), np.stack(truth_hdr))
    lpips, scores["lpips"] = lpips_scorer()
    for index, exposure in enumerate(views.exposures_s if lpips is not None else ()):
        truth_ldr = list(test.ldr[:, index])
        scores["ldr"][f"{exposure:g}"]["lpips"] = float(
            np.mean([lpips(p, t) for p, t in zip(views.ldr[index], truth_ldr, strict=True)])
        )
    middle = len(views.exposures_s) // 2
    scores["residual_blur"] = residual_blur(views.ldr[middle], list(test.ldr[:, middle]))
    scores["render_s_per_view"] = views.render_s
    return scores


def format_scores(metrics: dict) -> str:
    """One line per score of a ``metrics.json`` payload (the shared printout of fit and eval)."""
    lines = []
    if "hdr" in metrics:
        lines.append("at the test poses mapped from the training cameras:")
        lines.append(
            f"HDR (tone-mapped, one scale):     PSNR {metrics['hdr']['psnr']:.2f} dB  "
            f"SSIM {metrics['hdr']['ssim']:.4f}"
        )
        if "hdr_per_channel" in metrics:
            lines.append(
                f"HDR (a scale per channel):        PSNR "
                f"{metrics['hdr_per_channel']['psnr']:.2f} dB"
            )
        lines.append(
            f"HDR (tone-mapped, unaligned):     PSNR {metrics['hdr_unaligned']['psnr']:.2f} dB"
        )
        if "log_contrast" in metrics:
            contrast = ", ".join(f"{c:.3f}" for c in metrics["log_contrast"])
            lines.append(f"log contrast (1 is right):        {contrast}")
        novel = metrics["novel_exposure"]
        lines.append(
            f"novel exposures (2nd, 4th):       PSNR {novel['psnr']:.2f} dB  "
            f"SSIM {novel['ssim']:.4f}"
        )
        for exposure, score in metrics.get("ldr", {}).items():
            lpips = f"  LPIPS {score['lpips']:.4f}" if "lpips" in score else ""
            lines.append(
                f"  LDR {exposure:>8} s: PSNR {score['psnr']:.2f} dB  SSIM {score['ssim']:.4f}"
                + lpips
            )
        if "lpips" in metrics:
            lines.append(metrics["lpips"])
        if "residual_blur" in metrics:
            blur = metrics["residual_blur"]
            lines.append(
                f"sharpness: the middle exposure's views match the truth blurred by "
                f"{blur['sigma_px']:.3g} px (Gaussian sigma; {blur['psnr_gain']:+.2f} dB against "
                "the unblurred truth)"
            )
        poses = metrics.get("test_poses", {})
        if poses.get("registered"):
            registered = poses["registered_scores"]
            lines.append(
                f"extra, not the headline: each test pose refined against its own test image "
                f"(turned {poses['turned_deg_median']:.2f} deg median) gives HDR "
                f"{registered['hdr_psnr']:.2f} dB, novel {registered['novel_exposure_psnr']:.2f} dB"
            )
    else:
        lines.append("no ground truth: renders written, nothing scored")
    lines.append(f"render: {metrics.get('render_s_per_view', float('nan')):.2f} s per view")
    return "\n".join(lines)
