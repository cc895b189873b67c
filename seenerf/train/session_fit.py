"""``fit_session``: a prepared session's fit, in its run folder, on the data its variant reads."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from davis_io.session import DEFAULT_BINS, Session, writer_lock
from davis_io.session.folder import plain_name
from seenerf.data.arrays import TrainingData
from seenerf.data.session import load_training_data
from seenerf.model.config import FitConfig
from seenerf.model.variants import VARIANTS
from seenerf.train.fit import FitResult, fit_data
from seenerf.train.trainer import Trainer

__all__ = ["fit_session", "run_folder", "session_bins", "training_data"]


def session_bins(session_dir: Path | str, config: FitConfig) -> int:
    """B from the config, else the session manifest, else :data:`DEFAULT_BINS`."""
    if config.data.bins is not None:
        return config.data.bins
    with Session.open(session_dir) as session:
        return int(getattr(session.manifest, "b", 0) or DEFAULT_BINS)


def training_data(session_dir: Path | str, bins: int, config: FitConfig) -> TrainingData:
    """The session's training data as the configuration's variant reads it.

    A variant given the sensor's truth reads the emulator's values instead of the calibration's;
    a threshold the configuration states replaces the measured one.
    """
    return load_training_data(
        session_dir,
        bins,
        sensor_from_truth=VARIANTS[config.model.variant].sensor_from_truth,
        threshold=config.sensor.threshold,
    )


def run_folder(session_dir: Path | str, config: FitConfig, run_name: str | None) -> Path:
    """``session/fit/<run>/``: the run's name, or ``<preset>-<variant>`` by default.

    Raises:
        UsageError: ``run_name`` is not a plain folder name (a separator, ``..``, absolute).
    """
    name = plain_name(run_name, "--run") if run_name is not None else None
    return Path(session_dir) / "fit" / (name or f"{config.model.preset}-{config.model.variant}")


def fit_session(
    session_dir: Path | str,
    config: FitConfig,
    *,
    run_name: str | None = None,
    fresh: bool = False,
    log: Callable[[str], None] = print,
    spent_s: float = 0.0,
    on_step: Callable[[Trainer], None] | None = None,
) -> FitResult:
    """Fit a calibrated session with poses into ``session/fit/<run>/``.

    Args:
        session_dir: the session folder (``seecap fit`` calibrates it and estimates its poses
            first when missing: :func:`davis_io.prepare.prepare_session`).
        config: the fit configuration.
        run_name: run folder name (default ``<preset>-<variant>``).
        fresh: discard an existing checkpoint of this run instead of resuming it.
        log: receives progress lines.
        spent_s: seconds of the time budget already spent (calibration and poses).
        on_step: called with the trainer after every training step (a progress bar).
    """
    session_dir = Path(session_dir)
    start = time.perf_counter()
    run_dir = run_folder(session_dir, config, run_name)
    bins = session_bins(session_dir, config)
    with writer_lock(session_dir, f"fitting {run_dir.name}", shared=True):
        data = training_data(session_dir, bins, config)
        spent_s += time.perf_counter() - start
        return fit_data(
            data, config, run_dir, fresh=fresh, log=log, spent_s=spent_s, on_step=on_step
        )
