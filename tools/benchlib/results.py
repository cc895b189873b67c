"""One measured training run as a flat record, built from the fit's ``metrics.json``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["ProcessUsage", "RunRow", "row_from_metrics"]

NAN = math.nan


@dataclass(frozen=True)
class ProcessUsage:
    """What one child process cost.

    Attributes:
        returncode: exit status (negative: killed by that signal).
        wall_s: seconds from start to exit.
        cpu_s: user + system CPU seconds of the child.
        peak_rss_mb: the child's peak resident memory, MB (10^6 bytes).
        timed_out: the child was killed for overrunning its time limit.
    """

    returncode: int
    wall_s: float
    cpu_s: float
    peak_rss_mb: float
    timed_out: bool = False


@dataclass
class RunRow:
    """Scores and costs of one (session, preset, variant) run at one wall-clock budget.

    Attributes:
        session: benchmark session key (``room``, ``exposure-x16``, ...).
        preset: training preset.
        variant: model variant.
        budget_s: the time budget the run was given, s (cumulative over resumed rungs).
        seed: the fit's random seed (0: the default).
        step_cap: the step count the run was told to end at (0: the budget alone ended it;
            such runs match a comparison on steps, :mod:`benchlib.matching`).
        status: ``ok`` or what went wrong.
        steps: training steps completed in total.
        train_s: training seconds in total (resumed rungs included).
        stopped: why training stopped (``budget``, ``steps``, ``plateau``).
        rays_per_s: rendered rays per second of the last rung's steps.
        hdr_psnr: tone-mapped HDR PSNR of the held-out views at the test poses mapped from
            the training cameras, after one global scale, dB (the headline).
        hdr_ssim: tone-mapped HDR SSIM.
        hdr_unaligned_psnr: the same without the scale alignment, dB.
        novel_psnr: LDR PSNR at the novel exposures (bracket's 2nd and 4th), dB.
        novel_ssim: LDR SSIM at the novel exposures.
        ldr_psnr: LDR PSNR per test exposure, ``[(exposure_s, dB), ...]`` shortest first.
        fit_psnr: best PSNR on held-out pixels of the blurry training frames, dB.
        registered_hdr_psnr: HDR PSNR with each held-out pose refined against its own test
            image, dB (an extra column; NaN when not registered).
        registered_novel_psnr: novel-exposure PSNR likewise, dB.
        test_pose_turn_deg: how far registering each held-out view turned its mapped pose,
            degrees (the mapped poses' rotation error as the fitted scene sees it; empty when
            not registered).
        crf_rms: the learned response's RMS difference from the true one, worst channel.
        last_terms: the loss terms of the last progress record.
        render_s_per_view: seconds to render one test view.
        process: the rung's child process cost.
        reused: read back from an earlier invocation's kept metrics, not trained this time
            (``process`` is that invocation's).
    """

    session: str
    preset: str
    variant: str
    budget_s: float
    seed: int = 0
    step_cap: int = 0
    status: str = "ok"
    steps: int = 0
    train_s: float = NAN
    stopped: str = ""
    rays_per_s: float = NAN
    hdr_psnr: float = NAN
    hdr_ssim: float = NAN
    hdr_unaligned_psnr: float = NAN
    novel_psnr: float = NAN
    novel_ssim: float = NAN
    ldr_psnr: list[tuple[float, float]] = field(default_factory=list)
    fit_psnr: float = NAN
    registered_hdr_psnr: float = NAN
    registered_novel_psnr: float = NAN
    test_pose_turn_deg: list[float] = field(default_factory=list)
    crf_rms: float = NAN
    last_terms: dict[str, float] = field(default_factory=dict)
    render_s_per_view: float = NAN
    process: ProcessUsage | None = None
    reused: bool = False

    @property
    def ok(self) -> bool:
        """True when the run finished and was scored."""
        return self.status == "ok" and not math.isnan(self.hdr_psnr)


def _number(value) -> float:
    """A float, NaN for a missing value (JSON null, e.g. no evaluation before the budget)."""
    return NAN if value is None else float(value)


def _score(metrics: dict, name: str, key: str) -> float:
    return _number(metrics.get(name, {}).get(key))


def row_from_metrics(row: RunRow, metrics: dict) -> RunRow:
    """Fill ``row``'s scores and training figures from a ``metrics.json`` payload; return it.

    A payload without ``hdr`` (no ground truth) leaves the scores NaN and sets the status.
    """
    training = metrics.get("training", {})
    history = training.get("history") or [{}]
    row.steps = int(training.get("steps", 0))
    row.train_s = _number(training.get("elapsed_s"))
    row.stopped = str(training.get("stopped", ""))
    row.rays_per_s = _number(training.get("rays_per_s"))
    row.fit_psnr = _number(training.get("best_validation_psnr"))
    row.last_terms = {
        k: _number(v)
        for k, v in history[-1].items()
        if k not in ("step", "val_psnr", "steps_per_s", "elapsed_s")
    }
    row.render_s_per_view = _number(metrics.get("render_s_per_view"))
    if "hdr" not in metrics:
        row.status = "no ground truth in metrics.json"
        return row
    row.hdr_psnr, row.hdr_ssim = _score(metrics, "hdr", "psnr"), _score(metrics, "hdr", "ssim")
    row.hdr_unaligned_psnr = _score(metrics, "hdr_unaligned", "psnr")
    row.novel_psnr = _score(metrics, "novel_exposure", "psnr")
    row.novel_ssim = _score(metrics, "novel_exposure", "ssim")
    test_poses = metrics.get("test_poses", {})
    registered = test_poses.get("registered_scores", {})
    row.test_pose_turn_deg = [float(angle) for angle in test_poses.get("turned_deg", [])]
    row.registered_hdr_psnr = _number(registered.get("hdr_psnr"))
    row.registered_novel_psnr = _number(registered.get("novel_exposure_psnr"))
    crf = metrics.get("crf_error") or {}
    channels = [v for v in crf.get("rms", []) if v is not None and not math.isnan(v)]
    row.crf_rms = max(channels, default=NAN)
    ldr = metrics.get("ldr", {})
    row.ldr_psnr = sorted(
        (float(exposure), _number(score.get("psnr"))) for exposure, score in ldr.items()
    )
    return row
