"""What ``seecap fit`` does per session: make it ready, fit it, keep a failure to that session."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from davis_io import describe_error
from davis_io.prepare import estimate_preparation, prepare_session
from davis_io.session import read_manifest
from seenerf.errors import TrainingStopped
from seenerf.model.config import FitConfig
from seenerf.train.fit import FitResult, LogBook
from seenerf.train.session_fit import fit_session, session_bins
from seenerf.train.threads import choose_threads, limit_threads
from seenerf.train.trainer import Trainer

__all__ = ["SessionFit", "fit_kept_apart", "prepare_and_fit", "score_table"]


@dataclass
class SessionFit:
    """One session's fit among several: its run folder and scores, or why it failed.

    Attributes:
        session: the session folder as given.
        run_dir: the run folder (None when the fit failed before it existed).
        metrics: the run's ``metrics.json`` payload (None on failure).
        error: one line saying what went wrong ("" when fitted).
    """

    session: Path
    run_dir: Path | None = None
    metrics: dict | None = None
    error: str = ""


def prepare_and_fit(
    session_dir: Path | str,
    config: FitConfig,
    *,
    run_name: str | None = None,
    fresh: bool = False,
    log: Callable[[str], None] = print,
    on_step: Callable[[Trainer], None] | None = None,
    camera_calibration: Path | None = None,
) -> FitResult:
    """Calibrate the sensor and estimate poses when missing, then fit (the budget counts both).

    ``camera_calibration``: the lens's calibration file; poses made with another lens are
    estimated again.
    """
    book = LogBook(log)  # the calibration's and poses' lines go into the run's log.txt too
    read_manifest(session_dir)  # a folder without a session fails before the cores are timed
    threads, why = choose_threads(config.schedule.threads)
    limit_threads(threads)
    book(why)
    bins = session_bins(session_dir, config)
    budget_s = config.schedule.time_budget_s
    if budget_s is not None:
        plan = estimate_preparation(session_dir, bins)
        book(
            f"budget {budget_s:.0f} s: {plan.summary()}, then training and the final renders in "
            f"the {max(budget_s - plan.total_s, 0):.0f} s left"
        )
    spent_s = prepare_session(session_dir, bins, book, camera_calibration, threads=threads)
    return fit_session(
        session_dir,
        config,
        run_name=run_name,
        fresh=fresh,
        spent_s=spent_s,
        log=book,
        on_step=on_step,
    )


def fit_kept_apart(session_dir: Path | str, config: FitConfig, **options) -> SessionFit:
    """:func:`prepare_and_fit` with a failure kept as the session's error line.

    A stop asked for (Ctrl-C, SIGTERM) is not a failure of the session: it propagates.
    """
    try:
        result = prepare_and_fit(session_dir, config, **options)
    except TrainingStopped:
        raise
    except Exception as error:  # noqa: BLE001 - one session's failure must not end the others
        return SessionFit(Path(session_dir), error=describe_error(error))
    return SessionFit(Path(session_dir), result.run_dir, result.metrics)


def _cell(value: float | None, digits: int) -> str:
    return "-" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def score_table(fits: list[SessionFit]) -> str:
    """A fixed-width table: one row per session with its headline scores, or ``failed``."""
    header = ("session", "run", "HDR dB", "novel dB", "log contrast", "steps", "result")
    rows = [header]
    for fit in fits:
        metrics = fit.metrics or {}
        contrast = metrics.get("log_contrast")
        rows.append(
            (
                str(fit.session),
                fit.run_dir.name if fit.run_dir else "-",
                _cell(metrics.get("hdr", {}).get("psnr"), 2),
                _cell(metrics.get("novel_exposure", {}).get("psnr"), 2),
                _cell(sum(contrast) / len(contrast) if contrast else None, 3),
                str(metrics.get("training", {}).get("steps", "-")),
                "failed" if fit.error else "fitted",
            )
        )
    widths = [max(len(row[i]) for row in rows) for i in range(len(header))]
    return "\n".join(
        "  ".join(
            cell.ljust(width) if i < 2 else cell.rjust(width)
            for i, (cell, width) in enumerate(zip(row, widths, strict=True))
        ).rstrip()
        for row in rows
    )
