"""``fit_data``: training, renders, scores and exports of training data, in a run folder."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from davis_io import SeecapError
from davis_io.session import output_errors, writer_lock
from davis_io.session.folder import empty_folder
from seenerf.data.arrays import TrainingData
from seenerf.data.subframes import median_travel_px
from seenerf.errors import CheckpointError
from seenerf.eval.export import write_json
from seenerf.eval.outputs import render_outputs
from seenerf.eval.plots import training_curves
from seenerf.eval.report import is_session_run, write_report
from seenerf.model.config import FitConfig, save_config
from seenerf.provenance import software
from seenerf.sensors.rgb_crf import LinearCrf
from seenerf.train.builder import with_refined_poses
from seenerf.train.methods import Method, make_method
from seenerf.train.trainer import Trainer, TrainSummary

__all__ = [
    "FitResult",
    "LogBook",
    "clipped_events_note",
    "fit_data",
    "resolved_settings",
    "start_over",
]


@dataclass
class FitResult:
    """Outcome of a fit: where it was written, how training went, and the scores."""

    run_dir: Path
    summary: TrainSummary
    metrics: dict


def start_over(run_dir: Path) -> None:
    """Remove a run's checkpoint and outputs so that its next fit starts from scratch.

    Only what lies inside the run folder goes; a run folder that is a symbolic link is refused.
    """
    if run_dir.is_symlink():
        raise CheckpointError(
            f"{run_dir} is a symbolic link: --fresh empties only a run folder of the session's "
            "own; remove the link or choose another --run"
        )
    if not run_dir.is_dir():
        return
    with writer_lock(run_dir, f"clearing {run_dir.name}"):
        empty_folder(run_dir)


class LogBook:
    """A fit's lines, shown as they come and kept, time-stamped, in its run's ``log.txt``.

    Lines logged before the run folder is known (the calibration and poses of ``seecap fit``)
    are held and written first when :meth:`open` names the file.

    Args:
        show: receives every line (the progress display).
    """

    def __init__(self, show: Callable[[str], None] = print):
        self.show = show
        self.path: Path | None = None
        self._held: list[str] = []

    def __call__(self, line: str) -> None:
        """Show ``line`` and keep it."""
        stamped = f"{time.strftime('%Y-%m-%d %H:%M:%S')}  {line}\n"
        if self.path is None:
            self._held.append(stamped)
        else:
            self._write([stamped])
        self.show(line)

    def open(self, path: Path) -> LogBook:
        """From now on append to ``path``, the held lines first."""
        self.path = path
        held, self._held = self._held, []
        self._write(held)
        return self

    def _write(self, lines: list[str]) -> None:
        with output_errors(self.path), open(self.path, "a", encoding="utf-8") as file:
            file.writelines(lines)


def resolved_settings(method: Method) -> dict:
    """What a fit resolved for its scene, saved beside its config: field, box, space, sensor."""
    model, preset, data = method.model, method.preset, method.data
    renderer = model.renderer
    return {
        "field": preset.field,
        "field_args": preset.field_args,
        "bins": data.num_bins,
        "box": {"low": renderer.box.low, "high": renderer.box.high},
        "space": "ndc" if renderer.space is not None else "world",
        "event_weight": preset.event_weight,
        "clipped_event_factor": preset.clipped_event_factor,
        "clip_level": data.clip_level,
        "event_threshold": data.threshold,
        "event_cutoff_hz": data.cutoff_hz or method.config.sensor.cutoff_hz,
        "event_dead_time_s": model.event_crf.dead_time_s if model.event_crf is not None else 0.0,
        "rgb_response": None if model.crf is None else type(model.crf).__name__,
    }


def fit_data(
    data: TrainingData,
    config: FitConfig,
    run_dir: Path,
    *,
    fresh: bool = False,
    log: Callable[[str], None] = print,
    spent_s: float = 0.0,
    on_step: Callable[[Trainer], None] | None = None,
) -> FitResult:
    """Train on ``data`` in ``run_dir`` (resuming a checkpoint unless ``fresh``), render, score.

    Every line logged also goes to ``run_dir/log.txt`` (a :class:`LogBook` given as ``log``
    writes there the lines it held first). It computes with the threads the process has:
    ``seecap fit`` bounds them before the session is prepared
    (:func:`seenerf.cli.sessions.prepare_and_fit`).
    """
    with writer_lock(run_dir, f"fitting {run_dir.name}"):
        return _fit(data, config, run_dir, fresh, log, spent_s, on_step)


def _fit(data, config, run_dir, fresh, log, spent_s, on_step) -> FitResult:
    if fresh:
        start_over(run_dir)
    log = (log if isinstance(log, LogBook) else LogBook(log)).open(run_dir / "log.txt")
    method = make_method(data, config)
    trainer = Trainer(method, run_dir, log, spent_s, on_step)
    threads = torch.get_num_threads() if method.device == "cpu" else 0
    log(
        f"training {config.model.preset} {config.model.variant} on {method.device}"
        + (f" ({threads} threads)" if threads else "")
        + f", {data.num_frames} frames, b = {data.num_bins}"
    )
    travel_px = median_travel_px(data)
    log(
        f"image motion between latent poses: median {travel_px:.1f} px at the mean depth; "
        f"{config.model.subframes} pose(s) per bin in the blur integral"
    )
    lone = int(data.lone_frames.sum())
    if lone and config.data.lone_exposure_spans and method.model.event_crf is not None:
        log(
            f"{lone} of {data.num_frames} frames alone in their stretch of the event stream: "
            "their events are compared over the whole exposure as well as bin by bin "
            "(--no-lone-exposure-spans: bin by bin alone)"
        )
    clipped = clipped_events_note(method)
    if clipped:
        log(clipped)
    if isinstance(method.model.crf, LinearCrf):
        crf = method.model.crf
        log(
            f"frames measured linear: response linear above black {crf.black:.3f}, clipped at "
            f"{crf.saturation:.3f} (--response learned learns it instead)"
        )
    save_config(
        config,
        run_dir / "config.json",
        {**resolved_settings(method), "software": software(method.device)},
    )
    summary = trainer.train()
    log(
        f"trained {summary.steps} steps in {summary.elapsed_s:.0f} s ({summary.stopped}); "
        f"{summary.rays_per_s:.0f} rays/s"
    )
    if summary.skipped_steps:
        log(
            f"warning: {summary.skipped_steps} of {summary.steps} steps were skipped: their loss "
            "was not finite"
        )
    training_curves(run_dir / "training.png", summary.history)
    data, refined = _refined_poses(data, trainer.model, log)
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
        **refined,
    }
    write_json(run_dir / "metrics.json", metrics)
    if is_session_run(run_dir):
        try:
            log(f"report: {write_report(run_dir)}")
        except (SeecapError, OSError) as error:  # the renders and scores stand without it
            log(f"report.html not written ({error}); `seecap report {run_dir}` retries")
    return FitResult(run_dir, summary, metrics)


def clipped_events_note(method: Method) -> str:
    """What the fit does with the events of clipped pixels, one line ('' where nothing)."""
    data, factor = method.data, method.preset.clipped_event_factor
    if factor == 1.0 or method.model.event_crf is None:
        return ""
    share = float(np.mean(data.clipped(data.ldr)))
    if share == 0:
        return ""
    clipped = f"{share:.1%} of the frames' pixels clipped (at {data.clip_level:.3f}): "
    if not data.thresholds_measured:
        return clipped + "their events weigh as the others', as the thresholds are assumed"
    if not method.clips_hard:
        return clipped + "their events weigh as the others', the response telling how far above"
    return clipped + f"their events weigh {factor:g}x, the light above the clip level theirs alone"


def _refined_poses(data: TrainingData, model, log: Callable[[str], None]) -> tuple:
    """The data at the training poses the fit refined and how far each moved (logged too)."""
    if model.pose_correction is None:
        return data, {}
    turned, moved = model.pose_correction.sizes()
    log(
        f"training poses refined: turned {np.median(turned):.3f} deg median "
        f"({turned.max():.3f} largest), moved {np.median(moved):.4f} scene units median"
    )
    refined = {"poses_turned_deg": turned.tolist(), "poses_moved": moved.tolist()}
    return with_refined_poses(data, model), refined
