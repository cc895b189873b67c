"""Reopening a finished run: its model from ``config.json`` and the checkpoint; render, score."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from davis_io.geometry import OPENCV_TO_OPENGL
from davis_io.session.folder import plain_name
from seenerf.data.arrays import TrainingData
from seenerf.data.frames import test_poses_in_fit_frame
from seenerf.errors import CheckpointError
from seenerf.eval.export import write_json
from seenerf.eval.outputs import bracket_exposures, render_outputs
from seenerf.eval.video import video_frames, write_video
from seenerf.eval.views import render_views, write_views
from seenerf.model.config import FitConfig, load_config
from seenerf.model.model import SeeNerfModel
from seenerf.model.variants import VARIANTS
from seenerf.train.builder import build_model, resolve_device, with_refined_poses
from seenerf.train.checkpoint import load_model_state
from seenerf.train.methods import method_class
from seenerf.train.session_fit import training_data

__all__ = ["OpenRun", "evaluate_run", "open_run", "orbit_poses", "read_path", "render_run"]


@dataclass
class OpenRun:
    """A run's model (weights loaded), its training data and configuration."""

    run_dir: Path
    model: SeeNerfModel
    data: TrainingData
    config: FitConfig


def open_run(run_dir: Path | str) -> OpenRun:
    """Rebuild the model of ``session/fit/<run>/``.

    Raises:
        CheckpointError: no config or checkpoint in the folder.
    """
    run_dir = Path(run_dir)
    if not (run_dir / "checkpoint.pt").exists() or not (run_dir / "config.json").exists():
        raise CheckpointError(
            f"{run_dir}: not a fit run (config.json and checkpoint.pt expected); "
            "run seecap fit first"
        )
    config = load_config(run_dir / "config.json")
    bins = json.loads((run_dir / "config.json").read_text()).get("bins", config.data.bins)
    data = training_data(run_dir.parent.parent, int(bins), config)
    device = resolve_device(config.schedule.device)
    model, _ = build_model(data, config, device, method_class(VARIANTS[config.model.variant]))
    load_model_state(run_dir / "checkpoint.pt", model)
    return OpenRun(run_dir, model, with_refined_poses(data, model), config)


def orbit_poses(data: TrainingData, count: int = 60) -> np.ndarray:
    """A circle of ``count`` poses through the training cameras' spread, looking at their target.

    The circle lies in the plane of the camera centres' two main directions, centred on their
    mean, with the radius of their spread; every camera looks along the mean viewing direction.
    """
    centres = data.c2w[:, 0, :3, 3].astype(np.float64)
    mean = centres.mean(axis=0)
    _, spread, axes = np.linalg.svd(centres - mean)
    radius = max(float(spread[0]) / np.sqrt(max(len(centres), 1)), 1e-3)
    rotation = np.mean(data.c2w[:, 0, :3, :3], axis=0)
    u, _, vt = np.linalg.svd(rotation)
    rotation = u @ vt
    angles = np.linspace(0, 2 * np.pi, count, endpoint=False)
    poses = np.tile(np.eye(4), (count, 1, 1))
    poses[:, :3, :3] = rotation
    poses[:, :3, 3] = mean + radius * (
        np.cos(angles)[:, None] * axes[0] + np.sin(angles)[:, None] * axes[1]
    )
    return poses.astype(np.float32)


def read_path(path: Path) -> np.ndarray:
    """Camera path from a ``transforms.json`` (OpenGL axes) or a ``.npy`` of OpenCV ``(N, 4, 4)``.

    Raises:
        CheckpointError: unreadable file or wrong shape.
    """
    try:
        if path.suffix == ".json":
            frames = json.loads(path.read_text())["frames"]
            poses = np.array([f["transform_matrix"] for f in frames], float) @ OPENCV_TO_OPENGL
        else:
            poses = np.load(path, allow_pickle=False)
    except (OSError, KeyError, ValueError) as error:
        raise CheckpointError(f"{path}: not a camera path ({error})") from error
    if poses.ndim != 3 or poses.shape[1:] != (4, 4):
        raise CheckpointError(f"{path}: camera path must hold (N, 4, 4) poses, got {poses.shape}")
    return poses.astype(np.float32)


def render_run(
    run_dir: Path | str,
    exposures_s: tuple[float, ...] = (),
    path: str | None = None,
    out_name: str | None = None,
    video: Path | None = None,
    undistorted: bool = False,
) -> Path:
    """Render a run along a camera path (``orbit``, a file, or the held-out views if None).

    The views go to ``run_dir/out_name`` (default ``held-out`` or ``path``), never into the
    fit's own ``renders/``; with ``video``, also an MP4 there: at the one exposure given, or
    tone-mapped HDR. They are seen through the camera's lens, or with ``undistorted`` through
    a pinhole of its intrinsics (straight lines straight).

    Raises:
        davis_io.errors.UsageError: ``out_name`` is not a plain folder name.
        CheckpointError: a video asked for at several exposures, or not writable.
    """
    if video is not None and len(exposures_s) > 1:
        raise CheckpointError(
            f"--video {video}: a video shows one exposure (or, without --exposure, tone-mapped "
            f"HDR); {len(exposures_s)} were given"
        )
    if out_name is not None:
        plain_name(out_name, "--out")
    run = open_run(run_dir)
    if path is None:
        poses, _ = test_poses_in_fit_frame(run.data, run.model.in_truth_frame)
    else:
        poses = orbit_poses(run.data) if path == "orbit" else read_path(Path(path))
    exposures = exposures_s or bracket_exposures(run.config, run.data)
    out_name = out_name or ("held-out" if path is None else "path")
    distortion = None if undistorted else run.data.distortion
    views = render_views(
        run.model,
        poses,
        run.data.intrinsics,
        run.data.image_size,
        tuple(exposures),
        monochrome=run.data.monochrome,
        distortion=distortion,
    )
    out_dir = run.run_dir / out_name
    write_views(
        views,
        out_dir,
        run.data.intrinsics,
        run.data.image_size,
        {"seecap_variant": run.config.model.variant, "seecap_path": str(path or "held-out views")},
        distortion=distortion,
    )
    if video is not None:
        write_video(video, video_frames(views, exposures_s[0] if exposures_s else None))
    return out_dir


def evaluate_run(run_dir: Path | str) -> dict:
    """Re-render the held-out views of a run, score them, update ``metrics.json``."""
    run = open_run(run_dir)
    metrics_path = run.run_dir / "metrics.json"
    previous = json.loads(metrics_path.read_text()) if metrics_path.exists() else {}
    metrics = render_outputs(run.model, run.data, run.config, run.run_dir)
    if "training" in previous:
        metrics["training"] = previous["training"]
    write_json(metrics_path, metrics)
    return metrics
