"""Scores of rendered views against the truth, and their one-line-per-score printout."""

from __future__ import annotations

import math

import numpy as np

from seenerf.data.arrays import TrainingData
from seenerf.eval.metrics import hdr_metrics, ldr_metrics, log_contrast, residual_blur
from seenerf.eval.perceptual import lpips_scorer
from seenerf.eval.views import RenderedViews

__all__ = ["format_scores", "score_views", "truth_pairs"]


def truth_pairs(rendered_s: tuple[float, ...], truth_s: np.ndarray) -> dict[str, tuple[int, int]]:
    """``{exposure: (render index, truth index)}`` of the rendered exposures the truth holds.

    Renders and truth are paired by exposure time (to a relative 1e-6), never by position: a
    bracket asked for in another order, or with exposures the truth lacks, is scored right.
    """
    pairs = {}
    for index, exposure in enumerate(rendered_s):
        found = np.flatnonzero(np.isclose(truth_s, exposure, rtol=1e-6, atol=0.0))
        if len(found):
            pairs[f"{exposure:g}"] = (index, int(found[0]))
    return pairs


def score_views(views: RenderedViews, data: TrainingData, *, psnr_only: bool = False) -> dict:
    """PSNR / SSIM of HDR (tone-mapped after one scale; per-channel and raw beside) and of LDR.

    Each rendered exposure is scored against the truth's image at the same exposure (one the
    truth lacks is not scored). The novel-exposure score is the mean over the truth bracket's
    second and fourth exposures (the paper's protocol); ``residual_blur`` measures how sharp
    the views at the bracket's middle exposure are. LPIPS is added per exposure only when its
    weights are on this machine; ``lpips`` says which. With ``psnr_only`` the HDR (one scale),
    LDR and novel-exposure PSNRs alone, the SSIMs NaN: a second look at the same views from
    other poses.
    """
    test = data.test
    truth_hdr = list(test.hdr)
    structural = not psnr_only
    pairs = truth_pairs(views.exposures_s, np.asarray(test.exposures_s, dtype=float))
    scores = {"hdr": hdr_metrics(views.hdr, truth_hdr, "global", structural), "ldr": {}}
    for key, (rendered, truth) in pairs.items():
        scores["ldr"][key] = ldr_metrics(views.ldr[rendered], list(test.ldr[:, truth]), structural)
    bracket = [f"{exposure:g}" for exposure in np.sort(np.asarray(test.exposures_s, float))]
    novel = [scores["ldr"][bracket[i]] for i in (1, 3) if i < len(bracket) and bracket[i] in pairs]
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
    for key, (rendered, truth) in pairs.items() if lpips is not None else ():
        truth_ldr = list(test.ldr[:, truth])
        scores["ldr"][key]["lpips"] = float(
            np.mean([lpips(p, t) for p, t in zip(views.ldr[rendered], truth_ldr, strict=True)])
        )
    middle = bracket[len(bracket) // 2] if bracket else None
    if middle in pairs:
        rendered, truth = pairs[middle]
        scores["residual_blur"] = residual_blur(views.ldr[rendered], list(test.ldr[:, truth]))
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
            if _scored(novel["psnr"])
            else "novel exposures (2nd, 4th):       not scored (not among the exposures rendered)"
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
            novel_psnr = registered["novel_exposure_psnr"]
            lines.append(
                f"extra, not the headline: each test pose refined against its own test image "
                f"(turned {poses['turned_deg_median']:.2f} deg median) gives HDR "
                f"{registered['hdr_psnr']:.2f} dB"
                + (f", novel {novel_psnr:.2f} dB" if _scored(novel_psnr) else "")
            )
    else:
        lines.append("no ground truth: renders written, nothing scored")
    lines.append(f"render: {metrics.get('render_s_per_view', float('nan')):.2f} s per view")
    return "\n".join(lines)


def _scored(value: float | None) -> bool:
    """A score was computed (JSON keeps a missing one as null, Python as NaN)."""
    return value is not None and math.isfinite(value)
