"""``fit_session``: poses if missing, training, renders, scores and exports of one session."""

from __future__ import annotations

import importlib
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from davis_io.session import DEFAULT_BINS, Session
from seenerf.data.arrays import TrainingData
from seenerf.data.session import load_training_data
from seenerf.data.subframes import median_travel_px
from seenerf.errors import TrainingDataError
from seenerf.eval.export import write_json
from seenerf.eval.outputs import render_outputs
from seenerf.model.config import FitConfig, save_config
from seenerf.train.trainer import Trainer, TrainSummary

__all__ = ["FitResult", "ensure_poses", "fit_data", "fit_session"]


@dataclass
class FitResult:
    """Outcome of a fit: where it was written, how training went, and the scores."""

    run_dir: Path
    summary: TrainSummary
    metrics: dict


def ensure_poses(session_dir: Path, b: int, log: Callable[[str], None]) -> float:
    """Estimate poses for ``b`` if the session has none; return the seconds spent.

    Raises:
        TrainingDataError: poses are missing and the pose estimator is not available.
    """
    with Session.open(session_dir) as session:
        if session.poses(b) is not None:
            return 0.0
    try:
        estimate_poses = importlib.import_module("davis_io.poses").estimate_poses
    except (ImportError, AttributeError) as error:
        raise TrainingDataError(
            f"{session_dir}: no poses for b={b} and the pose estimator is unavailable ({error}); "
            "estimate poses first"
        ) from error
    log(f"estimating poses (b={b})")
    start = time.perf_counter()
    with Session.open(session_dir) as session:
        estimate_poses(session, b=b)
    return time.perf_counter() - start


def session_bins(session_dir: Path, config: FitConfig) -> int:
    """B from the config, else the session manifest, else :data:`DEFAULT_BINS`."""
    if config.bins:
        return config.bins
    with Session.open(session_dir) as session:
        return int(getattr(session.manifest, "b", 0) or DEFAULT_BINS)


def fit_session(
    session_dir: Path | str,
    config: FitConfig,
    *,
    run_name: str | None = None,
    fresh: bool = False,
    log: Callable[[str], None] = print,
) -> FitResult:
    """Fit a session end to end into ``session/fit/<run>/``.

    Args:
        session_dir: the session folder.
        config: the fit configuration (its time budget includes pose estimation).
        run_name: run folder name (default ``<preset>-<variant>``).
        fresh: discard an existing checkpoint of this run instead of resuming it.
        log: receives progress lines.
    """
    config = config.validate()
    session_dir = Path(session_dir)
    start = time.perf_counter()
    b = session_bins(session_dir, config)
    ensure_poses(session_dir, b, log)
    data = load_training_data(session_dir, b)
    run_dir = session_dir / "fit" / (run_name or f"{config.preset}-{config.variant}")
    return fit_data(
        data, config, run_dir, fresh=fresh, log=log, spent_s=time.perf_counter() - start
    )


def fit_data(
    data: TrainingData,
    config: FitConfig,
    run_dir: Path,
    *,
    fresh: bool = False,
    log: Callable[[str], None] = print,
    spent_s: float = 0.0,
) -> FitResult:
    """Train on ``data`` in ``run_dir`` (resuming a checkpoint unless ``fresh``), render, score."""
    if fresh and run_dir.exists():
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    trainer = Trainer(data, config, run_dir, log, spent_s)
    travel_px = median_travel_px(data)
    log(
        f"image motion between latent poses: median {travel_px:.1f} px at the mean depth; "
        f"{config.subframes} pose(s) per bin in the blur integral"
    )
    save_config(
        config,
        run_dir / "config.json",
        {
            "field": trainer.preset.field,
            "field_args": trainer.preset.field_args,
            "bins": data.num_bins,
            "box": {"low": trainer.model.renderer.box.low, "high": trainer.model.renderer.box.high},
            "space": "ndc" if trainer.model.renderer.space is not None else "world",
        },
    )
    summary = trainer.train()
    log(
        f"trained {summary.steps} steps in {summary.elapsed_s:.0f} s ({summary.stopped}); "
        f"{summary.rays_per_s:.0f} rays/s"
    )
    metrics = render_outputs(trainer.model, data, config, run_dir)
    metrics["training"] = {
        "steps": summary.steps,
        "elapsed_s": summary.elapsed_s,
        "stopped": summary.stopped,
        "rays_per_s": summary.rays_per_s,
        "samples_per_ray": summary.samples_per_ray,
        "best_validation_psnr": summary.best_psnr,
        "skipped_steps": summary.skipped_steps,
        "history": summary.history,
        "seconds_before_training": spent_s,
        "latent_travel_px": travel_px,
    }
    write_json(run_dir / "metrics.json", metrics)
    return FitResult(run_dir, summary, metrics)
