"""Renders a fitted model's views, writes them, and scores them against the truth when known."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from davis_io.geometry import Similarity, rotation_error_deg
from seenerf.data import TrainingData
from seenerf.evaluate import (
    align_channel_scale,
    hdr_metrics,
    ldr_metrics,
    log_contrast,
    residual_blur,
)
from seenerf.export import (
    crf_plot,
    tone_mapped_preview,
    transforms_json,
    write_exr,
    write_json,
    write_png,
)
from seenerf.model import SeeNerfModel
from seenerf.perceptual import lpips_scorer
from seenerf.registration import register_view
from seenerf.sensors.rgb_crf import TabulatedCrf
from seenerf.views import IDENTITY, render_log_image, truth_to_fit_frame

__all__ = [
    "PAPER_EXPOSURES_S",
    "RenderedViews",
    "crf_error",
    "learned_crf",
    "plot_crf",
    "register_test_poses",
    "render_views",
    "score_views",
    "test_poses_in_fit_frame",
    "write_views",
]

PAPER_EXPOSURES_S = (0.001, 0.004, 0.016, 0.064, 0.256)
"""The paper's LDR bracket, used when neither the config nor the truth names exposures."""

_LUMINANCE = np.array([0.2126, 0.7152, 0.0722], np.float32)


@dataclass
class RenderedViews:
    """Rendered views in the fit's frame.

    Attributes:
        c2w: ``(V, 4, 4)`` poses rendered (fit frame).
        hdr: linear HDR images ``(H, W, C)``; ``ldr[e]`` the images at ``exposures_s[e]``.
        render_s: seconds per view.
    """

    c2w: np.ndarray
    exposures_s: tuple[float, ...]
    hdr: list[np.ndarray] = field(default_factory=list)
    ldr: list[list[np.ndarray]] = field(default_factory=list)
    render_s: float = 0.0


@torch.no_grad()
def render_views(
    model: SeeNerfModel,
    c2w: np.ndarray,
    intrinsics: np.ndarray,
    image_size: tuple[int, int],
    exposures_s: tuple[float, ...],
    monochrome: bool,
) -> RenderedViews:
    """HDR and LDR images of each pose; a monochrome sensor's views are luminance ``(H, W, 1)``."""
    model.eval()
    views = RenderedViews(np.asarray(c2w), tuple(exposures_s), ldr=[[] for _ in exposures_s])
    start = time.perf_counter()
    for pose in views.c2w:
        log_image = torch.as_tensor(render_log_image(model, pose, intrinsics, image_size))
        if monochrome:
            hdr = model.hdr_from_log(log_image).numpy() @ _LUMINANCE
            log_lum = torch.log(torch.as_tensor(hdr).clamp(min=1e-30))[..., None].expand(-1, -1, 3)
            views.hdr.append(hdr[..., None])
            for index, ldr in enumerate(model.ldr_images(log_lum, exposures_s)):
                views.ldr[index].append(ldr[..., :1].numpy())
        else:
            views.hdr.append(model.hdr_from_log(log_image).numpy())
            for index, ldr in enumerate(model.ldr_images(log_image, exposures_s)):
                views.ldr[index].append(ldr.numpy())
    views.render_s = (time.perf_counter() - start) / max(len(views.c2w), 1)
    return views


def score_views(views: RenderedViews, data: TrainingData) -> dict:
    """PSNR / SSIM of HDR (tone-mapped, per-channel scale aligned and raw) and of each LDR exposure.

    The novel-exposure score is the mean over the bracket's second and fourth exposures (the
    paper's protocol). ``residual_blur`` measures how sharp the views at the bracket's middle
    exposure are. LPIPS is added per exposure only when its weights are on this machine;
    ``lpips`` says which.
    """
    test = data.test
    truth_hdr = list(test.hdr)
    scores = {
        "hdr": hdr_metrics(views.hdr, truth_hdr, align=True),
        "hdr_unaligned": hdr_metrics(views.hdr, truth_hdr, align=False),
        "log_contrast": log_contrast(np.stack(views.hdr), np.stack(truth_hdr)),
        "ldr": {},
    }
    lpips, scores["lpips"] = lpips_scorer()
    for index, exposure in enumerate(views.exposures_s):
        truth_ldr = list(test.ldr[:, index])
        scores["ldr"][f"{exposure:g}"] = ldr_metrics(views.ldr[index], truth_ldr)
        if lpips is not None:
            scores["ldr"][f"{exposure:g}"]["lpips"] = float(
                np.mean([lpips(p, t) for p, t in zip(views.ldr[index], truth_ldr, strict=True)])
            )
    middle = len(views.exposures_s) // 2
    scores["residual_blur"] = residual_blur(views.ldr[middle], list(test.ldr[:, middle]))
    novel = [
        scores["ldr"][f"{views.exposures_s[i]:g}"] for i in (1, 3) if i < len(views.exposures_s)
    ]
    scores["novel_exposure"] = {
        "psnr": float(np.mean([m["psnr"] for m in novel])) if novel else float("nan"),
        "ssim": float(np.mean([m["ssim"] for m in novel])) if novel else float("nan"),
    }
    scores["render_s_per_view"] = views.render_s
    return scores


def write_views(
    views: RenderedViews,
    run_dir: Path,
    intrinsics: np.ndarray,
    image_size: tuple[int, int],
    metadata: dict,
) -> None:
    """EXR + tone-mapped PNG per view, LDR PNGs per exposure, and ``transforms.json``."""
    names = []
    for index, hdr in enumerate(views.hdr):
        name = f"{index:03d}"
        write_exr(run_dir / "renders" / "hdr" / f"{name}.exr", hdr, metadata)
        write_png(run_dir / "renders" / "hdr" / f"{name}.png", tone_mapped_preview(hdr))
        for exposure, images in zip(views.exposures_s, views.ldr, strict=True):
            write_png(run_dir / "renders" / "ldr" / f"{exposure:g}" / f"{name}.png", images[index])
        names.append(f"renders/hdr/{name}.png")
    write_json(
        run_dir / "transforms.json", transforms_json(views.c2w, intrinsics, image_size, names)
    )


def test_poses_in_fit_frame(
    data: TrainingData, trained_in_truth_frame: bool
) -> tuple[np.ndarray, Similarity]:
    """Test poses mapped into the fit's frame, or each frame's first latent pose without truth."""
    if data.test is None:
        return data.c2w[:, 0], IDENTITY
    similarity = IDENTITY if trained_in_truth_frame else truth_to_fit_frame(data)
    return similarity.apply_poses(data.test.c2w).astype(np.float32), similarity


def register_test_poses(
    model: SeeNerfModel, data: TrainingData, c2w: np.ndarray
) -> tuple[np.ndarray, dict]:
    """Each held-out pose refined against its LDR image at the exposure nearest the training one.

    Returns:
        The refined ``(V, 4, 4)`` poses and a summary: the exposure used, how far the poses
        turned (median and largest, degrees) and the seconds per view.
    """
    exposures = np.asarray(data.test.exposures_s, np.float64)
    index = int(np.argmin(np.abs(np.log(exposures / model.reference_exposure_s))))
    start = time.perf_counter()
    refined = np.stack(
        [
            register_view(
                model,
                pose,
                data.intrinsics,
                data.test.ldr[view, index],
                float(exposures[index]),
                seed=view,
            )
            for view, pose in enumerate(c2w)
        ]
    )
    turned = rotation_error_deg(np.asarray(c2w)[:, :3, :3], refined[:, :3, :3])
    return refined, {
        "registered": True,
        "exposure_s": float(exposures[index]),
        "turned_deg_median": float(np.median(turned)),
        "turned_deg_max": float(np.max(turned)),
        "s_per_view": (time.perf_counter() - start) / max(len(c2w), 1),
    }


def learned_crf(
    model: SeeNerfModel, data: TrainingData, views: RenderedViews
) -> tuple[np.ndarray, np.ndarray] | None:
    """The learned response ``(x, (N, 3) values)`` on the truth's ln(radiance x s) axis.

    The model's radiance is known up to the CRF anchor; its per-channel HDR scale against the
    truth (when scored) shifts the curve onto the truth's axis. None without a learned CRF.
    """
    if model.crf is None or isinstance(model.crf, TabulatedCrf):
        return None
    log_exposure = np.linspace(-8.0, 6.0, 141, dtype=np.float32)
    with torch.no_grad():
        values = model.crf(torch.as_tensor(log_exposure)[:, None].expand(-1, 3)).numpy()
    shift = 0.0
    if data.test is not None and views.hdr:
        scale = align_channel_scale(np.stack(views.hdr), data.test.hdr)
        shift = float(np.log(np.mean(scale)))
    return log_exposure + shift, values


def _true_crf(data: TrainingData) -> tuple[np.ndarray, np.ndarray] | None:
    truth = data.truth
    if truth is None or not len(truth.crf_value):
        return None
    return np.asarray(truth.crf_log_exposure), np.asarray(truth.crf_value)


def _channels_in_use(data: TrainingData) -> tuple[int, ...]:
    """The response curves the sensor's pixels go through (a monochrome sensor: the first)."""
    return tuple(int(c) for c in np.unique(data.channel))


def plot_crf(model: SeeNerfModel, data: TrainingData, views: RenderedViews, path: Path) -> None:
    """The learned response beside the true one, when the model has one: the curves in use."""
    learned = learned_crf(model, data, views)
    if learned is not None:
        crf_plot(path, learned, _true_crf(data), _channels_in_use(data))


def crf_error(model: SeeNerfModel, data: TrainingData, views: RenderedViews) -> dict | None:
    """RMS and largest difference of the learned and the true response, per channel in use.

    Only the curves the sensor's pixels go through are compared (a monochrome sensor uses the
    first; the others are never trained), where the true response is between 0.01 and 0.99
    (below and above, every curve clips) and the learned curve was evaluated. Returns
    ``{"channels": [...], "rms": [...], "max": [...]}``, or None without a CRF or a true one.
    """
    learned, true = learned_crf(model, data, views), _true_crf(data)
    if learned is None or true is None:
        return None
    (x, values), (true_x, true_values) = learned, true
    inside = (true_x >= x[0]) & (true_x <= x[-1])
    channels = list(_channels_in_use(data))
    rms, largest = [], []
    for channel in channels:
        reference = true_values[:, min(channel, true_values.shape[1] - 1)]
        keep = inside & (reference > 0.01) & (reference < 0.99)
        difference = np.interp(true_x[keep], x, values[:, channel]) - reference[keep]
        rms.append(float(np.sqrt(np.mean(difference**2))) if keep.any() else float("nan"))
        largest.append(float(np.max(np.abs(difference))) if keep.any() else float("nan"))
    return {"channels": channels, "rms": rms, "max": largest}
