"""Fits of several sessions as Ray tasks, on this machine or on a cluster: the one seam for Ray.

Ray is imported here only, and only when a command is given ``--ray``. Every node must see the
session folders at the same absolute paths (shared storage); a fit writes its run folder exactly
as a local fit does, so a task that is started again after its worker died resumes from the
run's checkpoint.
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path

from davis_io import describe_error
from seenerf.cli.sessions import SessionFit, fit_kept_apart
from seenerf.errors import ConfigError
from seenerf.model.config import FitConfig
from seenerf.train.fit import start_over
from seenerf.train.session_fit import run_folder
from seenerf.train.trainer import TrainingProgress

__all__ = [
    "RAY_MISSING",
    "RETRIES",
    "cancel_tasks",
    "fit_on_ray",
    "import_ray",
    "ray_connection",
]

RAY_MISSING = "Ray is not installed: pip install -e '.[cluster]' installs it (or pip install ray)"

RETRIES = 3
"""Times a fit is started again after its worker died; each retry resumes from the checkpoint."""

PROGRESS_EVERY_S = 2.0
"""Seconds between the progress reports of a running fit."""

POLL_S = 0.5
"""Seconds between two looks at the running fits."""

CANCEL_WAIT_S = 60.0
"""Seconds Ctrl-C waits for the cancelled fits to save their checkpoints."""

LOCAL_OBJECT_STORE_BYTES = 256 * 2**20
"""The object store of a local instance: fits return a few kilobytes each."""


def import_ray():
    """The ``ray`` module, or a usage error naming the command that installs it."""
    try:
        import ray
    except ImportError as error:
        raise ConfigError(RAY_MISSING) from error
    return ray


@contextmanager
def ray_connection(address: str, cpus: int | None = None) -> Iterator[object]:
    """Ray connected while inside; shut down after if this call started it.

    Args:
        address: ``local`` starts an instance on this machine (loopback only, no dashboard),
            ``auto`` joins the one ``ray start --head`` started here, anything else is the
            address of a cluster's head (``HOST:6379`` or ``ray://HOST:10001``).
        cpus: CPUs a local instance offers (None: every core of this machine).

    Raises:
        ConfigError: Ray is not installed, or no cluster answers at ``address``.
    """
    ray = import_ray()
    if ray.is_initialized():  # a caller's instance (tests, a notebook): used and left running
        yield ray
        return
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")  # nothing leaves the machine
    quiet = {"log_to_driver": False, "logging_level": logging.ERROR}
    try:
        if address == "local":
            ray.init(
                address="local",  # a new instance, even where `ray start` made one
                num_cpus=cpus,
                include_dashboard=False,
                _node_ip_address="127.0.0.1",
                object_store_memory=LOCAL_OBJECT_STORE_BYTES,
                **quiet,
            )
        else:
            ray.init(address=address, **quiet)
    except ConnectionError as error:
        raise ConfigError(
            f"no Ray cluster answers at {address!r} ({error}): start one with `ray start "
            "--head` (and `ray start --address HEAD:6379` on each worker), or use --ray local"
        ) from error
    except Exception as error:  # noqa: BLE001 - Ray raises a bare Exception when a node stalls
        raise ConfigError(
            f"Ray did not start at {address!r} ({error}): on a busy machine run again when it "
            "is quieter, or start Ray yourself (`ray start --head`) and use --ray auto"
        ) from error
    try:
        yield ray
    finally:
        ray.shutdown()


def cancel_tasks(ray, refs: list, wait_s: float = 0.0) -> None:
    """Cancel Ray tasks (a running one is interrupted); wait up to ``wait_s`` for them to end."""
    for ref in refs:
        ray.cancel(ref)
    if refs and wait_s > 0:
        ray.wait(refs, num_returns=len(refs), timeout=wait_s)


class _Progress:
    """What the running fits report (a Ray actor: every worker reaches it, the driver reads it)."""

    def __init__(self):
        self.lines: list[tuple[int, str]] = []
        self.latest: dict[int, TrainingProgress] = {}

    def line(self, index: int, text: str) -> None:
        self.lines.append((index, text))

    def progress(self, index: int, progress: TrainingProgress) -> None:
        self.latest[index] = progress

    def take(self) -> tuple[list[tuple[int, str]], dict[int, TrainingProgress]]:
        taken = self.lines, self.latest
        self.lines, self.latest = [], {}
        return taken


def _fit_task(index: int, session: str, config: FitConfig, run_name, progress) -> SessionFit:
    """One session's fit in a worker, reporting its lines and (every few seconds) its progress."""
    reported, latest = -math.inf, None

    def on_step(trainer) -> None:
        nonlocal reported, latest
        latest = trainer.training_progress()
        if time.monotonic() - reported >= PROGRESS_EVERY_S:
            progress.progress.remote(index, latest)
            reported = time.monotonic()

    fit = fit_kept_apart(
        session,
        config,
        run_name=run_name,
        log=lambda text: progress.line.remote(index, text),
        on_step=on_step,
    )
    if latest is not None:  # the last step, whenever the last report was
        progress.progress.remote(index, latest)
    return fit


def _gathered(ray, ref, session: Path) -> SessionFit:
    """A finished task's fit, or the failure Ray reports for it."""
    try:
        return ray.get(ref)
    except ray.exceptions.RayTaskError as error:
        return SessionFit(session, error=describe_error(error.cause or error))
    except ray.exceptions.RayError as error:
        return SessionFit(
            session,
            error=f"its worker died {RETRIES + 1} times ({type(error).__name__}); the checkpoint "
            "is kept: run the same command again to resume",
        )


def fit_on_ray(
    sessions: list[Path],
    config: FitConfig,
    *,
    address: str,
    run_name: str | None = None,
    fresh: bool = False,
    on_line: Callable[[int, str], None] = lambda index, text: None,
    on_progress: Callable[[int, TrainingProgress], None] = lambda index, progress: None,
) -> list[SessionFit]:
    """Fit each session as a Ray task; return their fits in the order given.

    Each task declares ``config.schedule.threads`` CPUs (1 when not given) and one GPU with
    ``device='cuda'``, and is started again up to :data:`RETRIES` times when its worker dies. A
    session that fails is returned with its error and does not stop the others. Ctrl-C cancels
    every task (each saves its checkpoint) before it propagates.

    Args:
        sessions: session folders every node sees at the same absolute paths.
        config: the fit configuration of every session.
        address: where Ray runs (:func:`ray_connection`).
        run_name: run folder name under each ``session/fit/``.
        fresh: start every run over instead of resuming it.
        on_line: receives (session index, line) for each line a fit logs.
        on_progress: receives (session index, progress) every few seconds of each fit.
    """
    absolute = [Path(session).resolve() for session in sessions]
    if fresh:  # here, not in the task: a retried task must resume, not start over again
        for session in absolute:
            start_over(run_folder(session, config, run_name))
    config = config.replaced(threads=config.schedule.threads or 1)
    with ray_connection(address) as ray:
        progress = ray.remote(num_cpus=0)(_Progress).remote()
        task = ray.remote(_fit_task).options(
            num_cpus=config.schedule.threads,
            num_gpus=1 if config.schedule.device == "cuda" else 0,
            max_retries=RETRIES,
            retry_exceptions=False,
        )
        pending = {
            task.remote(index, str(session), config, run_name, progress): index
            for index, session in enumerate(absolute)
        }
        fits: list[SessionFit | None] = [None] * len(sessions)

        def relay() -> None:
            lines, latest = ray.get(progress.take.remote())
            for index, text in lines:
                on_line(index, text)
            for index, state in latest.items():
                on_progress(index, state)

        try:
            while pending:
                done, _ = ray.wait(list(pending), num_returns=len(pending), timeout=POLL_S)
                relay()
                for ref in done:
                    index = pending.pop(ref)
                    fits[index] = _gathered(ray, ref, Path(sessions[index]))
        except KeyboardInterrupt:
            cancel_tasks(ray, list(pending), wait_s=CANCEL_WAIT_S)
            raise
    return [replace(fit, session=Path(given)) for fit, given in zip(fits, sessions, strict=True)]
