"""Trains one budget ladder: ``seecap fit`` in its own process per rung, resuming the same run."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from benchlib.plan import Ladder
from benchlib.results import ProcessUsage, RunRow, row_from_metrics
from benchlib.runner import python_command, run_measured, usage_from_json

__all__ = [
    "KEPT_KEY",
    "SpeedProbe",
    "fit_command",
    "kept_path",
    "kept_row",
    "ladder_goes_on",
    "reusable_rungs",
    "rung_line",
    "rung_row",
    "run_ladder",
    "run_name",
    "run_speed_probe",
    "train_rung",
]

KEPT_KEY = "bench"
"""Key the benchmark adds to a rung's kept ``metrics.json``: the session folder it was trained
on and the rung's process cost, so a later invocation can read the rung back."""

FIT_OVERHEAD_S = 900.0
"""Time a rung may take beyond its budget (imports, data, warm start, renders) before a kill."""

TOOLS_DIR = Path(__file__).resolve().parents[1]


@dataclass
class SpeedProbe:
    """Rays per second of every preset, trained a few steps each in one process.

    Attributes:
        rays_per_s: preset name -> rays/s, plus ``fast_over_paper``.
        usage: the probe process's cost.
        error: what failed ("" when measured).
    """

    rays_per_s: dict[str, float] = field(default_factory=dict)
    usage: ProcessUsage | None = None
    error: str = ""


def run_name(ladder: Ladder) -> str:
    """Run folder name under ``session/fit/`` (with the seed unless it is the default, and the
    step count it ends at if any)."""
    name = f"bench-{ladder.preset}-{ladder.variant}"
    name = f"{name}-seed{ladder.seed}" if ladder.seed else name
    return f"{name}-steps{ladder.steps}" if ladder.steps else name


def rung_row(ladder: Ladder, index: int, **fields) -> RunRow:
    """The row of rung ``index`` of ``ladder``, before anything is read into it."""
    return RunRow(
        ladder.session,
        ladder.preset,
        ladder.variant,
        ladder.budgets_s[index],
        seed=ladder.seed,
        step_cap=ladder.steps,
        **fields,
    )


def fit_command(session_dir: Path, ladder: Ladder, budget_s: float, fresh: bool) -> list[str]:
    """``seecap fit`` arguments of one rung (a fresh run for the first, a resume after)."""
    command = python_command(
        "-m",
        "davis_io.cli",
        "fit",
        str(session_dir),
        "--preset",
        ladder.preset,
        "--variant",
        ladder.variant,
        "--time-budget",
        f"{budget_s:g}s",
        "--run",
        run_name(ladder),
        "--seed",
        str(ladder.seed),
    )
    return (
        command
        + (["--steps", str(ladder.steps)] if ladder.steps else [])
        + (["--fresh"] if fresh else [])
    )


def _failure(log: Path, returncode: int, timed_out: bool) -> str:
    lines = [line for line in log.read_text(errors="replace").splitlines() if line.strip()]
    last = lines[-1] if lines else "no output"
    cause = "killed after its time limit" if timed_out else f"exit {returncode}"
    return f"failed ({cause}): {last[:200]}"


def run_speed_probe(session_dir: Path, log_dir: Path, steps: int = 10) -> SpeedProbe:
    """Run :mod:`benchlib.speed_probe` on a session in its own process and read its JSON line."""
    log = log_dir / "speed-probe.log"
    command = python_command(
        "-m", "benchlib.speed_probe", "--session", str(session_dir), "--steps", str(steps)
    )
    probe = SpeedProbe(usage=run_measured(command, log, cwd=TOOLS_DIR, timeout_s=FIT_OVERHEAD_S))
    for line in reversed(log.read_text(errors="replace").splitlines()):
        if line.startswith('{"rays_per_s"'):
            probe.rays_per_s = json.loads(line)["rays_per_s"]
            return probe
    probe.error = _failure(log, probe.usage.returncode, probe.usage.timed_out)
    return probe


def kept_path(out_dir: Path, ladder: Ladder, budget_s: float) -> Path:
    """Where a rung's metrics are kept: ``OUT/runs/SESSION/RUN/BUDGETs.json``."""
    return out_dir / "runs" / ladder.session / run_name(ladder) / f"{budget_s:g}s.json"


def _read_kept(path: Path, session_dir: Path) -> dict | None:
    """The kept metrics at ``path`` if they were trained on ``session_dir`` (else None)."""
    try:
        metrics = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    made = metrics.get(KEPT_KEY, {})
    return metrics if made.get("session_dir") == str(session_dir) and "process" in made else None


def reusable_rungs(ladder: Ladder, session_dir: Path, out_dir: Path) -> list[dict]:
    """Kept metrics of the ladder's leading rungs that an earlier invocation already trained.

    A rung is read back when its kept metrics exist, were made on this session folder, and the
    run folder still holds the checkpoint the next rung resumes. Only a leading run of such
    rungs counts: once one rung is trained again, every later one must be too. None counts
    when a rung above the first one to train was kept (by a ladder of other budgets): the
    checkpoint may then be past that rung's budget, so the ladder starts over.
    """
    if not (session_dir / "fit" / run_name(ladder) / "checkpoint.pt").exists():
        return []
    kept = []
    for budget in ladder.budgets_s:
        metrics = _read_kept(kept_path(out_dir, ladder, budget), session_dir)
        if metrics is None:
            break
        kept.append(metrics)
    if len(kept) < len(ladder.budgets_s):
        next_budget = ladder.budgets_s[len(kept)]
        folder = kept_path(out_dir, ladder, next_budget).parent
        if any(_kept_budget(path) > next_budget for path in folder.glob("*s.json")):
            return []
    return kept


def _kept_budget(path: Path) -> float:
    """The budget a kept file's name gives (``180s.json`` -> 180.0; NaN if none)."""
    try:
        return float(path.name.removesuffix("s.json"))
    except ValueError:
        return float("nan")


def _keep(path: Path, metrics: dict, session_dir: Path, usage: ProcessUsage) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    made = {"session_dir": str(session_dir), "process": dataclasses.asdict(usage)}
    path.write_text(json.dumps({**metrics, KEPT_KEY: made}, indent=1) + "\n")


def kept_row(ladder: Ladder, index: int, metrics: dict) -> RunRow:
    """The row of a rung an earlier invocation trained, read back from its kept metrics."""
    row = rung_row(ladder, index, reused=True)
    row.process = usage_from_json(metrics[KEPT_KEY]["process"])
    return row_from_metrics(row, metrics)


def train_rung(
    ladder: Ladder,
    index: int,
    session_dir: Path,
    out_dir: Path,
    *,
    first_trained: bool,
    threads: int = 0,
) -> RunRow:
    """Train rung ``index`` in its own ``seecap fit`` process (resuming the rung before it).

    Args:
        ladder: session, preset, variant and budgets.
        index: which budget of the ladder.
        session_dir: the prepared session folder.
        out_dir: the benchmark's output folder (logs and per-rung metrics go under it).
        first_trained: the first rung this invocation trains: the kept metrics of its budget
            and every larger one are removed, since its training changes their checkpoint.
        threads: torch threads of the fit (0: torch's default, every core).

    Returns:
        The rung's scored row, or a row whose status says why it failed.
    """
    budget = ladder.budgets_s[index]
    row = rung_row(ladder, index)
    if first_trained:
        for path in kept_path(out_dir, ladder, budget).parent.glob("*s.json"):
            if not _kept_budget(path) < budget:  # this rung's, later ones, unreadable
                path.unlink()
    name = run_name(ladder)
    log = out_dir / "logs" / ladder.session / name / f"{budget:g}s.log"
    command = fit_command(session_dir, ladder, budget, fresh=index == 0)
    row.process = run_measured(
        command + (["--threads", str(threads)] if threads else []),
        log,
        timeout_s=budget + FIT_OVERHEAD_S,
    )
    metrics_path = session_dir / "fit" / name / "metrics.json"
    if row.process.returncode != 0 or not metrics_path.exists():
        row.status = _failure(log, row.process.returncode, row.process.timed_out)
        return row
    metrics = json.loads(metrics_path.read_text())
    _keep(kept_path(out_dir, ladder, budget), metrics, session_dir, row.process)
    return row_from_metrics(row, metrics)


def ladder_goes_on(row: RunRow) -> bool:
    """Whether the rung above ``row`` is trained: not after a failure or an early stop."""
    return row.ok and row.stopped == "budget"


def rung_line(ladder: Ladder, row: RunRow) -> str:
    """One progress line of a rung of ``ladder``: its scores and cost, or its failure."""
    tag = f"{ladder.session}/{run_name(ladder)}/{row.budget_s:g}s"
    if not row.ok:
        return f"{tag}: {row.status}"
    usage = row.process
    how = "read back" if row.reused else f"{usage.wall_s:.0f} s wall, {usage.peak_rss_mb:.0f} MB"
    return (
        f"{tag}: HDR {row.hdr_psnr:.2f} dB, novel {row.novel_psnr:.2f} dB, "
        f"{row.steps} steps in {row.train_s:.0f} s ({row.stopped}), {how}"
    )


def run_ladder(
    ladder: Ladder,
    session_dir: Path,
    out_dir: Path,
    *,
    fresh: bool = False,
    threads: int = 0,
    progress: Callable[[str], None] = print,
) -> list[RunRow]:
    """Train ``ladder`` up each budget in turn; one scored row per rung.

    Each rung resumes the previous rung's checkpoint, so the 10-minute row costs 10 minutes of
    training in total, not 1 + 3 + 10. A rung that fails, or whose run already stopped before
    its budget (step count or plateau), ends the ladder. Rungs an earlier invocation finished
    (:func:`reusable_rungs`) are read back, not trained, unless ``fresh``.

    Args:
        ladder: session, preset, variant and budgets.
        session_dir: the prepared session folder.
        out_dir: the benchmark's output folder (logs and per-rung metrics go under it).
        fresh: train every rung, the first from scratch, ignoring earlier invocations.
        threads: torch threads of each fit (0: torch's default, every core).
        progress: receives one line per rung.
    """
    rows = []
    kept = [] if fresh else reusable_rungs(ladder, session_dir, out_dir)
    for index in range(len(ladder.budgets_s)):
        if index < len(kept):
            row = kept_row(ladder, index, kept[index])
        else:
            first = index == len(kept)
            row = train_rung(
                ladder, index, session_dir, out_dir, first_trained=first, threads=threads
            )
        rows.append(row)
        progress(rung_line(ladder, row))
        if not ladder_goes_on(row):
            break
    return rows
