"""Every rung of the plan as a Ray task: a ladder's rungs chained, the ladders side by side."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TypeVar

from benchlib.fits import (
    kept_row,
    ladder_goes_on,
    reusable_rungs,
    rung_line,
    rung_row,
    train_rung,
)
from benchlib.plan import Ladder
from benchlib.results import RunRow
from davis_io import describe_error
from seenerf.cli.cluster import RETRIES, cancel_tasks, ray_connection

__all__ = ["FIT_THREADS", "map_on_ray", "run_ladders_on_ray"]

T = TypeVar("T")
R = TypeVar("R")

FIT_THREADS = 1
"""CPUs each rung's task declares, and its fit's torch threads."""

TOOLS_DIR = Path(__file__).resolve().parents[1]


def _rung_task(
    previous: RunRow | None, ladder: Ladder, index: int, session_dir: Path, out_dir: Path, first
) -> RunRow | None:
    """Train one rung once the rung below it is done; None when the ladder ended below it."""
    if previous is not None and not ladder_goes_on(previous):
        return None
    return train_rung(ladder, index, session_dir, out_dir, first_trained=first, threads=FIT_THREADS)


def _task(ray, function: Callable, cpus: int):
    """``function`` as a Ray task of ``cpus`` CPUs whose workers import ``benchlib`` from here."""
    path = os.pathsep.join(filter(None, [str(TOOLS_DIR), os.environ.get("PYTHONPATH")]))
    return ray.remote(function).options(
        num_cpus=cpus, max_retries=RETRIES, runtime_env={"env_vars": {"PYTHONPATH": path}}
    )


def map_on_ray(
    function: Callable[[T], R], items: list[T], *, address: str, cpus: int
) -> Iterator[R]:
    """``function(item)`` for each item as a Ray task of ``cpus`` CPUs; results as they finish."""
    with ray_connection(address) as ray:
        task = _task(ray, function, cpus)
        pending = [task.remote(item) for item in items]
        try:
            while pending:
                (ref,), pending = ray.wait(pending, num_returns=1)
                yield ray.get(ref)
        except BaseException:  # Ctrl-C, or the caller stopped early: nothing left running
            cancel_tasks(ray, pending)
            raise


def run_ladders_on_ray(
    ladders: list[tuple[Ladder, Path]],
    out_dir: Path,
    *,
    address: str,
    fresh: bool = False,
    progress: Callable[[str], None] = print,
) -> list[list[RunRow]]:
    """Train each (ladder, session folder) with every rung a Ray task; rows per ladder, in order.

    A ladder's rungs form a chain (each task takes the row below it, so it starts when that
    rung is done and stops the ladder as :func:`benchlib.fits.run_ladder` does); the chains
    run side by side, one CPU each. Rungs an earlier invocation kept are read back here.

    Args:
        ladders: each ladder with its prepared session folder (on storage every node sees).
        out_dir: the benchmark's output folder (likewise).
        address: where Ray runs (:func:`seenerf.cli.cluster.ray_connection`).
        fresh: train every rung, ignoring earlier invocations.
        progress: receives one line per rung as it finishes.
    """
    with ray_connection(address) as ray:
        rung = _task(ray, _rung_task, FIT_THREADS)
        chains, pending = [], {}
        for ladder, session_dir in ladders:
            kept = [] if fresh else reusable_rungs(ladder, session_dir, out_dir)
            rows = [kept_row(ladder, index, metrics) for index, metrics in enumerate(kept)]
            below, refs = (rows[-1] if rows else None), []
            for index in range(len(kept), len(ladder.budgets_s)):
                first = index == len(kept)
                below = rung.remote(below, ladder, index, session_dir, out_dir, first)
                refs.append(below)
                pending[below] = (ladder, index)
            chains.append((rows, refs))
        finished = {}
        try:
            while pending:
                (ref,), _ = ray.wait(list(pending), num_returns=1)
                ladder, index = pending.pop(ref)
                finished[ref] = _finished_row(ray, ref, ladder, index)
                if finished[ref] is not None:
                    progress(rung_line(ladder, finished[ref]))
        except KeyboardInterrupt:  # each running rung kills its fit's process group
            cancel_tasks(ray, list(pending))
            raise
    return [rows + _up_to_the_end(finished[ref] for ref in refs) for rows, refs in chains]


def _finished_row(ray, ref, ladder: Ladder, index: int) -> RunRow | None:
    """A finished rung task's row; a failed task (its worker died each time) as a failed row."""
    try:
        return ray.get(ref)
    except ray.exceptions.RayError as error:
        failure = f"failed ({type(error).__name__}): {describe_error(error)[:200]}"
        return rung_row(ladder, index, status=failure)


def _up_to_the_end(rows) -> list[RunRow]:
    """A chain's rows up to where its ladder ended (a failure is the last one kept)."""
    kept = []
    for row in rows:
        if row is None:
            break
        kept.append(row)
        if not row.ok:
            break
    return kept
