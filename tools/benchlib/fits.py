"""Trains one budget ladder: ``seecap fit`` in its own process per rung, resuming the same run."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from benchlib.plan import Ladder
from benchlib.results import ProcessUsage, RunRow, row_from_metrics
from benchlib.runner import python_command, run_measured

__all__ = ["SpeedProbe", "fit_command", "run_ladder", "run_name", "run_speed_probe"]

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
    """Run folder name under ``session/fit/``."""
    return f"bench-{ladder.preset}-{ladder.variant}"


def fit_command(session_dir: Path, ladder: Ladder, budget_s: float, fresh: bool) -> list[str]:
    """``seecap fit`` arguments of one rung (a fresh run for the first, a resume after)."""
    command = python_command("-m", "davis_io.cli", "fit", str(session_dir), "--preset",
                             ladder.preset, "--variant", ladder.variant, "--time-budget",
                             f"{budget_s:g}s", "--run", run_name(ladder))
    return command + (["--fresh"] if fresh else [])


def _failure(log: Path, returncode: int, timed_out: bool) -> str:
    lines = [line for line in log.read_text(errors="replace").splitlines() if line.strip()]
    last = lines[-1] if lines else "no output"
    cause = "killed after its time limit" if timed_out else f"exit {returncode}"
    return f"failed ({cause}): {last[:200]}"


def run_speed_probe(session_dir: Path, log_dir: Path, steps: int = 10) -> SpeedProbe:
    """Run :mod:`benchlib.speed_probe` on a session in its own process and read its JSON line."""
    log = log_dir / "speed-probe.log"
    command = python_command("-m", "benchlib.speed_probe", "--session", str(session_dir),
                             "--steps", str(steps))
    probe = SpeedProbe(usage=run_measured(command, log, cwd=TOOLS_DIR, timeout_s=FIT_OVERHEAD_S))
    for line in reversed(log.read_text(errors="replace").splitlines()):
        if line.startswith('{"rays_per_s"'):
            probe.rays_per_s = json.loads(line)["rays_per_s"]
            return probe
    probe.error = _failure(log, probe.usage.returncode, probe.usage.timed_out)
    return probe


def run_ladder(ladder: Ladder, session_dir: Path, out_dir: Path,
               progress: Callable[[str], None] = print) -> list[RunRow]:
    """Train ``ladder`` up each budget in turn; one scored row per rung.

    Each rung resumes the previous rung's checkpoint, so the 10-minute row costs 10 minutes of
    training in total, not 1 + 3 + 10. A rung that fails, or whose run already stopped before
    its budget (step count or plateau), ends the ladder.

    Args:
        ladder: session, preset, variant and budgets.
        session_dir: the prepared session folder.
        out_dir: the benchmark's output folder (logs and per-rung metrics go under it).
        progress: receives one line per rung.
    """
    rows = []
    name = run_name(ladder)
    for index, budget in enumerate(ladder.budgets_s):
        tag = f"{ladder.session}/{name}/{budget:g}s"
        log = out_dir / "logs" / ladder.session / name / f"{budget:g}s.log"
        usage = run_measured(fit_command(session_dir, ladder, budget, fresh=index == 0), log,
                             timeout_s=budget + FIT_OVERHEAD_S)
        row = RunRow(ladder.session, ladder.preset, ladder.variant, budget, process=usage)
        metrics_path = session_dir / "fit" / name / "metrics.json"
        if usage.returncode != 0 or not metrics_path.exists():
            row.status = _failure(log, usage.returncode, usage.timed_out)
            rows.append(row)
            progress(f"{tag}: {row.status}")
            break
        kept = out_dir / "runs" / ladder.session / name / f"{budget:g}s.json"
        kept.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(metrics_path, kept)
        rows.append(row_from_metrics(row, json.loads(metrics_path.read_text())))
        progress(f"{tag}: HDR {row.hdr_psnr:.2f} dB, novel {row.novel_psnr:.2f} dB, "
                 f"{row.steps} steps in {row.train_s:.0f} s ({row.stopped}), "
                 f"{usage.wall_s:.0f} s wall, {usage.peak_rss_mb:.0f} MB")
        if row.stopped != "budget":
            break
    return rows
