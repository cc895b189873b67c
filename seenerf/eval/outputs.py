"""Everything a fitted model leaves in its run: held-out views rendered, written and scored."""

from __future__ import annotations

from pathlib import Path

from seenerf.data.arrays import TrainingData
from seenerf.data.frames import IDENTITY, test_poses_in_fit_frame
from seenerf.eval.crf import crf_error, plot_crf
from seenerf.eval.registration import register_test_poses
from seenerf.eval.scores import score_views
from seenerf.eval.views import PAPER_EXPOSURES_S, render_views, write_views
from seenerf.model.config import FitConfig
from seenerf.model.model import SeeNerfModel

__all__ = ["bracket_exposures", "render_outputs"]


def bracket_exposures(config: FitConfig, data: TrainingData) -> tuple[float, ...]:
    """The LDR exposures a run renders: the configured ones, else the truth's, else the paper's."""
    if config.output.exposures_s:
        return tuple(config.output.exposures_s)
    if data.test is not None:
        return tuple(float(exposure) for exposure in data.test.exposures_s)
    return PAPER_EXPOSURES_S


def render_outputs(
    model: SeeNerfModel, data: TrainingData, config: FitConfig, run_dir: Path
) -> dict:
    """Render the held-out (or training) views, write every output file, return the scores.

    The held-out views are rendered at the true test poses mapped into the fit's frame by the
    similarity of the training cameras (the headline scores, and the written renders). With
    ``register_test_views``, each pose is also refined against its own test image and the
    views scored again there: a labelled extra (``test_poses.registered_scores``), never the
    headline.
    """
    poses, similarity = test_poses_in_fit_frame(data, model.in_truth_frame)
    exposures = bracket_exposures(config, data)
    views = render_views(
        model,
        poses,
        data.intrinsics,
        data.image_size,
        exposures,
        data.monochrome,
        distortion=data.distortion,
    )
    write_views(
        views,
        run_dir,
        data.intrinsics,
        data.image_size,
        {
            "seecap_variant": config.model.variant,
            "seecap_preset": config.model.preset,
            "seecap_units": "linear radiance, scale of the learned CRF anchor",
        },
        distortion=data.distortion,
    )
    plot_crf(model, data, views, run_dir / "crf.png")
    metrics = {
        "variant": config.model.variant,
        "preset": config.model.preset,
        "similarity_scale": similarity.scale,
        "render_s_per_view": views.render_s,
    }
    if data.test is None:
        return metrics
    metrics.update(score_views(views, data))
    metrics["crf_error"] = crf_error(model, data, views)
    metrics["test_poses"] = {"mapped_by": "similarity of the training cameras", "registered": False}
    if config.output.register_test_views and similarity is not IDENTITY:
        refined, registration = register_test_poses(model, data, poses)
        registered = score_views(
            render_views(
                model,
                refined,
                data.intrinsics,
                data.image_size,
                exposures,
                data.monochrome,
                distortion=data.distortion,
            ),
            data,
            psnr_only=True,
        )
        metrics["test_poses"].update(
            registration,
            registered_scores={
                "hdr_psnr": registered["hdr"]["psnr"],
                "novel_exposure_psnr": registered["novel_exposure"]["psnr"],
            },
        )
    return metrics
