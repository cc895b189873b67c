"""The training loop: batches, losses, Adam, occupancy refresh, progress, checkpoints, stops."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import torch

from seenerf.errors import TrainingDataError, TrainingStopped
from seenerf.model.pose_correction import LEARNING_RATE as POSE_LEARNING_RATE
from seenerf.train.checkpoint import load_checkpoint, save_checkpoint
from seenerf.train.methods import Method
from seenerf.train.stopping import StopRequest, stop_requests
from seenerf.train.threads import CoreWatch, limit_threads, threads_beside

__all__ = ["TrainSummary", "Trainer", "TrainingProgress"]

GRID_WARMUP_STEPS = 50
"""Steps before the first occupancy refresh (the field is still blank before)."""

CHECKPOINT_EVERY_S = 60.0
"""Seconds of training between checkpoints besides those at every evaluation: a killed fit
loses at most this much."""

OUTPUT_RENDERS_PER_VIEW = 6.0
"""A held-out view's share of the work after training, in renders of it: rendered, registered
against its image (about four renders' worth: 1.5 s against 0.4 s per view on 2 cores) and
rendered again."""

OUTPUT_FIXED_S = 8.0
"""Scores, plots and the last checkpoint after training, seconds."""

THREADS_CHECK_S = 30.0
"""Seconds of training between looks at how busy other work keeps the cores (automatic threads
only): a fit that started alone gives a core up when another process starts, and takes it back
when it ends."""

SKIPPED_IN_A_ROW_LIMIT = 50
"""Steps in a row without a finite loss after which a fit stops as failed: nothing is learned."""

PLATEAU_FROM_PROGRESS = 0.5
"""Share of the run (steps or budget) before a plateau may stop it: a 10-minute fit of the
emulated room stopped at 44 % with the rate still 2.5x its final value (5,000 steps; the held-out
score had not gained 0.05 dB in 8 evaluations while it wobbled)."""


@dataclass
class TrainSummary:
    """What a training run did.

    Attributes:
        steps: steps completed (including resumed ones).
        elapsed_s: training seconds (including resumed ones).
        stopped: ``steps``, ``budget`` or ``plateau``.
        best_psnr: best held-out LDR PSNR of the progress evaluations, dB.
        rays_per_s: rendered rays per second over this process's steps.
        samples_per_ray: mean field queries per ray in the last step.
        skipped_steps: steps whose loss was not finite (no update made).
        history: progress records (step, losses, PSNR, rate).
    """

    steps: int = 0
    elapsed_s: float = 0.0
    stopped: str = "steps"
    best_psnr: float = -math.inf
    rays_per_s: float = 0.0
    samples_per_ray: float = 0.0
    skipped_steps: int = 0
    history: list = field(default_factory=list)


@dataclass(frozen=True)
class TrainingProgress:
    """Where a training run stands, for a progress display (small: it may cross processes).

    Attributes:
        steps: steps completed (including resumed ones).
        elapsed_s: training seconds (including resumed ones).
        total_steps: the step count that ends the run (inf: none).
        budget_s: training seconds the time budget leaves after preparation (inf: none).
    """

    steps: int
    elapsed_s: float
    total_steps: float
    budget_s: float


class Trainer:
    """Trains one method's model: steps, learning rate, budget, checkpoints, progress, stops.

    What is trained, on which data and with which loss terms is the method's
    (:func:`~seenerf.train.methods.make_method`); the schedule is its configuration's.

    Args:
        method: the fit's method, its model built.
        run_dir: folder for the checkpoint (None: no checkpoints).
        log: receives every progress line.
        spent_s: seconds already spent by the caller (poses) against the time budget.
        on_step: ``on_step(trainer)`` after every step (a progress bar), or None.
    """

    def __init__(
        self,
        method: Method,
        run_dir: Path | None = None,
        log: Callable[[str], None] = print,
        spent_s: float = 0.0,
        on_step: Callable[[Trainer], None] | None = None,
    ):
        self.method, self.run_dir, self.log, self.on_step = method, run_dir, log, on_step
        self.data, self.config, self.device = method.data, method.config, method.device
        self.model, self.preset = method.model, method.preset
        config = self.config
        self.generator = torch.Generator().manual_seed(config.schedule.seed)
        # A budget alone runs until it is spent or the held-out score stops rising (a plateau),
        # not to the preset's step count: that count only sets how far the rate falls.
        if config.schedule.steps is not None:
            self.total_steps = config.schedule.steps
        else:
            budgeted = config.schedule.time_budget_s is not None
            self.total_steps = math.inf if budgeted else self.preset.steps
        self.spent_s = spent_s
        automatic = config.schedule.threads is None and self.device == "cpu"
        self.core_watch = CoreWatch() if automatic else None
        self.cores_looked_at = time.perf_counter()
        field_params = list(self.model.renderer.parameters())
        sensor_params = [
            p
            for name, p in self.model.named_parameters()
            if not name.startswith(("renderer.", "pose_correction."))
        ]
        groups = [(field_params, self.preset.lr), (sensor_params, self.preset.sensor_lr)]
        if self.model.pose_correction is not None:
            groups.append((list(self.model.pose_correction.parameters()), POSE_LEARNING_RATE))
        self.base_rates = [rate for _, rate in groups]
        self.optimizer = torch.optim.Adam(
            [{"params": params, "lr": rate} for params, rate in groups],
            betas=(0.9, 0.999),
            fused=True,  # one kernel over every tensor: 6x faster than the loop on a CPU
        )
        self.summary = TrainSummary()
        self.evals_since_best = 0
        self.last_step_skipped = False
        self.outputs_s = 0.0
        """Seconds kept from the budget for the renders and scores after training."""

    def train(self) -> TrainSummary:
        """Run (or resume) training until the step count, the time budget or a plateau.

        SIGTERM and Ctrl-C end it after the current step with a checkpoint of that step.

        Raises:
            TrainingStopped: a stop was asked for (the checkpoint is saved; rerun to resume).
        """
        resumed = self._resume()
        if not resumed:
            self.model.warm_start(self.preset.warm_steps, self.config.schedule.seed)
        with stop_requests() as stop:
            return self._train(stop)

    def _train(self, stop: StopRequest) -> TrainSummary:
        start, start_step, rays = time.perf_counter(), self.summary.steps, 0
        base_elapsed = self.summary.elapsed_s
        saved_at = start
        skipped_before = self.summary.skipped_steps
        while self.summary.steps < self.total_steps:
            rays += self._step()
            self.summary.steps += 1
            skipped_before = self._check_skipped(skipped_before)
            self.summary.elapsed_s = base_elapsed + time.perf_counter() - start
            if self.on_step is not None:
                self.on_step(self)
            if stop.signal_number is not None:
                self._checkpoint()
                where = self.run_dir / "checkpoint.pt" if self.run_dir else "nowhere"
                raise TrainingStopped(
                    f"stopped at step {self.summary.steps} ({stop.signal_name}); checkpoint "
                    f"saved in {where}: run the same seecap fit again to resume",
                    stop.signal_number,
                )
            if time.perf_counter() - saved_at > CHECKPOINT_EVERY_S:
                self._checkpoint()
                saved_at = time.perf_counter()
            self._share_cores()
            if self._budget_left() <= 0:
                self.summary.stopped = "budget"
                break
            if self.summary.steps % self.preset.eval_every == 0 and self._evaluate(
                start_step, start
            ):
                self.summary.stopped = "plateau"
                break
        self.summary.rays_per_s = rays / max(time.perf_counter() - start, 1e-9)
        self._checkpoint()
        return self.summary

    def _share_cores(self) -> None:
        """With automatic threads, every :data:`THREADS_CHECK_S`, one per core others leave."""
        if self.core_watch is None or time.perf_counter() - self.cores_looked_at < THREADS_CHECK_S:
            return
        self.cores_looked_at = time.perf_counter()
        others = self.core_watch.others()
        if others is None:
            return
        count = threads_beside(others)
        if count != torch.get_num_threads():
            limit_threads(count)
            self.log(f"threads: {count} from now on ({others:.1f} cores busy with other work)")

    def _check_skipped(self, skipped_before: int) -> int:
        """Fail once :data:`SKIPPED_IN_A_ROW_LIMIT` steps in a row had no finite loss.

        Returns:
            The skipped count a run of skipped steps began at (the current count after a
            finite step).

        Raises:
            TrainingDataError: the limit was reached: the options or the data make every loss
                NaN or infinite.
        """
        skipped = self.summary.skipped_steps
        if skipped - skipped_before < SKIPPED_IN_A_ROW_LIMIT:
            return skipped_before if self.last_step_skipped else skipped
        raise TrainingDataError(
            f"the loss was not finite in {SKIPPED_IN_A_ROW_LIMIT} steps in a row (to step "
            f"{self.summary.steps}; {skipped} skipped in all), so nothing was learned: check the "
            "fit's options (weights, thresholds) and the session (seecap inspect)"
        )

    def _training_budget(self) -> float:
        """Training seconds the budget leaves; inf without a budget.

        What the caller spent (calibration, poses) and what the final renders and scores will
        take (:attr:`outputs_s`) are not the training's.
        """
        if self.config.schedule.time_budget_s is None:
            return math.inf
        return self.config.schedule.time_budget_s - self.spent_s - self.outputs_s

    def _estimate_outputs(self, validation_s: float) -> None:
        """What the renders and scores after training will take, from the validation's speed.

        Each held-out view is rendered, registered against its image and rendered again
        (:data:`OUTPUT_RENDERS_PER_VIEW` renders' worth), plus :data:`OUTPUT_FIXED_S`.
        """
        rays = len(self.method.validation) * (self.data.num_bins * self.config.model.subframes + 1)
        if rays == 0 or validation_s <= 0:
            return
        height, width = self.data.image_size
        views = len(self.data.test.c2w) if self.data.test is not None else self.data.num_frames
        render_s = height * width * validation_s / rays
        first = self.outputs_s == 0.0
        self.outputs_s = views * OUTPUT_RENDERS_PER_VIEW * render_s + OUTPUT_FIXED_S
        budget_s = self.config.schedule.time_budget_s
        if first and budget_s is not None:
            self.log(
                f"keeping {self.outputs_s:.0f} s of the {budget_s:.0f} s budget "
                f"for the final renders and scores of {views} views ({self.spent_s:.0f} s went "
                "to calibration and poses)"
            )

    def training_progress(self) -> TrainingProgress:
        """Steps and seconds done against the run's step count and time budget."""
        return TrainingProgress(
            self.summary.steps, self.summary.elapsed_s, self.total_steps, self._training_budget()
        )

    def _budget_left(self) -> float:
        return self._training_budget() - self.summary.elapsed_s

    def _step(self) -> int:
        step = self.summary.steps
        self._set_learning_rate()
        if (
            self.model.renderer.grid is not None
            and step >= GRID_WARMUP_STEPS
            and step % self.preset.grid_every == 0
        ):
            self.model.renderer.grid.update(self.model.renderer.density, self.generator)
        step_terms = self.method.step(self.generator)
        loss = step_terms.loss()
        self.optimizer.zero_grad(set_to_none=True)
        self.last_step_skipped = not bool(torch.isfinite(loss))
        if self.last_step_skipped:
            self.summary.skipped_steps += 1
            return step_terms.rays
        loss.backward()
        self.optimizer.step()
        self.summary.samples_per_ray = step_terms.samples / max(step_terms.rays, 1)
        self.last_terms = step_terms.shown()
        return step_terms.rays

    def progress(self) -> float:
        """How far the run is, 0 to 1: the larger of its share of the steps and of the budget.

        The time share is the training seconds over what the budget leaves after the caller's
        (poses); a run without a budget counts steps only.
        """
        progress = self.summary.steps / max(self.total_steps, 1)  # 0 without a step count
        training_budget = self._training_budget()
        if 0 < training_budget < math.inf:
            progress = max(progress, self.summary.elapsed_s / training_budget)
        return min(progress, 1.0)

    def _set_learning_rate(self) -> None:
        """The rate falls 10x every ``lr_decay_steps`` of the steps taken.

        A run that its time budget ends falls only as far as the steps it took, never faster
        than the preset's step count spread over the budget: a field that had time for few
        steps is still forming when the budget ends, and an anneal as deep as a full run's
        stalls it (``room``, three minutes, 1,500 steps: 28.9 dB HDR annealed to the preset's
        0.25x, 30.8 dB annealed as a run of that many steps, to 0.68x).
        """
        steps = self.total_steps if math.isfinite(self.total_steps) else self.preset.steps
        taken = min(self.summary.steps, self.progress() * steps)
        decades = taken / self.preset.lr_decay_steps
        factor = 0.1**decades
        for group, base in zip(self.optimizer.param_groups, self.base_rates, strict=True):
            group["lr"] = base * factor

    def validation_psnr(self) -> float:
        """The method's held-out score, dB (the blurry frames' LDR PSNR for a recording)."""
        return self.method.validation_psnr()

    def _evaluate(self, start_step: int, start: float) -> bool:
        began = time.perf_counter()
        value = self.validation_psnr()
        self._estimate_outputs(time.perf_counter() - began)
        rate = (self.summary.steps - start_step) / max(time.perf_counter() - start, 1e-9)
        remaining = (self.total_steps - self.summary.steps) / max(rate, 1e-9)
        eta = min(remaining, self._budget_left())
        terms = getattr(self, "last_terms", {})
        of = f"/{self.total_steps}" if math.isfinite(self.total_steps) else ""
        self.log(
            f"step {self.summary.steps}{of}  "
            + "  ".join(f"{k} {v:.4g}" for k, v in terms.items())
            + f"  val PSNR {value:.2f} dB  {rate:.2f} steps/s  ETA {eta:.0f} s"
        )
        self.summary.history.append(
            {
                "step": self.summary.steps,
                **terms,
                "val_psnr": value,
                "steps_per_s": rate,
                "elapsed_s": self.summary.elapsed_s,
            }
        )
        if value > self.summary.best_psnr + 0.05:
            self.summary.best_psnr, self.evals_since_best = value, 0
        else:
            self.evals_since_best += 1
        self._checkpoint()
        return self.plateaued()

    def plateaued(self) -> bool:
        """The held-out score has not risen for ``patience`` evaluations in the run's second half.

        While the rate is still high the score wobbles by more than a plateau's margin, so a run
        stops early only once half its schedule (steps or budget) is behind it.
        """
        settled = self.progress() >= PLATEAU_FROM_PROGRESS
        return settled and 0 < self.preset.patience <= self.evals_since_best

    def _checkpoint(self) -> None:
        if self.run_dir is not None:
            save_checkpoint(self.run_dir / "checkpoint.pt", self)

    def _resume(self) -> bool:
        if self.run_dir is None or not (self.run_dir / "checkpoint.pt").exists():
            return False
        load_checkpoint(self.run_dir / "checkpoint.pt", self)
        self.log(f"resuming at step {self.summary.steps} from {self.run_dir / 'checkpoint.pt'}")
        return True
