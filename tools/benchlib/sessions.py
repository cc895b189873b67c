"""Benchmark sessions: recorded once under the output folder, with poses, and reused by reruns."""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

from benchlib.plan import SessionSpec
from benchlib.results import ProcessUsage
from benchlib.runner import python_command, run_measured
from davis_io.errors import DavisIOError
from davis_io.poses.truth import compare_with_truth
from davis_io.session import Session, read_manifest
from davis_io.session.truth import load_truth

__all__ = ["BINS", "SessionOutcome", "prepare_session"]

BINS = 4
"""Event bins per exposure of every fit (the paper's b)."""

TOOLS_DIR = Path(__file__).resolve().parents[1]
SESSION_TIMEOUT_S = 3600.0


@dataclass
class SessionOutcome:
    """A session ready for fitting, or why it is not.

    Attributes:
        spec: what was asked for.
        folder: the session folder.
        cached: it was already complete (nothing recorded this time).
        record: cost of recording it this time (None when cached).
        poses: cost of its pose step this time (None when poses were already stored).
        record_s: seconds its recording took (this time, or when it was made).
        poses_s: seconds the pose step itself reported (estimation or truth copy), this time or
            when it was made.
        frames: recorded frames.
        events: recorded events.
        registered: latent poses registered by the estimator (not interpolated).
        latent: latent poses in all, frames x (b + 1).
        rotation_error_deg: median rotation error of the registered poses after alignment to
            the truth, degrees (NaN with fewer than 3 registered).
        centre_error: median camera-centre error over the scene extent (NaN likewise).
        error: what failed ("" when ready).
    """

    spec: SessionSpec
    folder: Path
    cached: bool = False
    record: ProcessUsage | None = None
    poses: ProcessUsage | None = None
    record_s: float = math.nan
    poses_s: float = math.nan
    frames: int = 0
    events: int = 0
    registered: int = 0
    latent: int = 0
    rotation_error_deg: float = math.nan
    centre_error: float = math.nan
    error: str = ""


def _is_complete(folder: Path) -> bool:
    try:
        complete = read_manifest(folder).status == "complete"
    except DavisIOError:
        return False
    return complete and (folder / "truth" / "truth.h5").exists()


def _costs_path(folder: Path) -> Path:
    """Where the seconds spent making a session are kept, beside (not inside) the session."""
    return folder.parent / f"{folder.name}.costs.json"


def _load_costs(outcome: SessionOutcome) -> None:
    path = _costs_path(outcome.folder)
    if path.exists():
        costs = json.loads(path.read_text())
        outcome.record_s = costs.get("record_s", math.nan)
        outcome.poses_s = costs.get("poses_s", math.nan)


def _save_costs(outcome: SessionOutcome) -> None:
    costs = {"record_s": outcome.record_s, "poses_s": outcome.poses_s}
    _costs_path(outcome.folder).write_text(json.dumps(costs) + "\n")


def _has_poses(folder: Path) -> bool:
    """Poses and the sensor's calibration both stored (what every fit reads)."""
    with Session.open(folder) as session:
        return session.poses(BINS) is not None and session.calibration() is not None


def _record_command(spec: SessionSpec, folder: Path, views: tuple[int, int]) -> list[str]:
    if spec.maker == "benchmark":
        command = python_command(
            str(TOOLS_DIR / "make_benchmark.py"),
            "--out",
            str(folder.parent),
            "--only",
            spec.key,
            "--no-aedat",
            "--overwrite",
        )
        return command + (["--quick"] if views == (4, 2) else [])
    return python_command(
        "-m",
        "benchlib.bracket_session",
        "--out",
        str(folder),
        "--scene",
        spec.scene,
        "--seed",
        str(spec.seed),
        "--exposure-us",
        str(spec.exposure_us),
        "--gain-exposure-us",
        str(spec.gain_exposure_us),
        "--noise-scale",
        f"{spec.noise_scale:g}",
        "--frames",
        str(views[0]),
        "--test-views",
        str(views[1]),
    )


def _log_tail(path: Path) -> str:
    lines = [line for line in path.read_text(errors="replace").splitlines() if line.strip()]
    return lines[-1] if lines else "no output"


def prepare_session(
    spec: SessionSpec, root: Path, views: tuple[int, int], poses: str, log_dir: Path
) -> SessionOutcome:
    """Record ``spec`` under ``root`` unless complete there, then store poses unless present.

    ``make_benchmark.py`` sessions are made with its fixed views (``--quick`` for 4 + 2);
    the others by :mod:`benchlib.bracket_session` with ``views``.
    """
    folder = root / spec.key
    outcome = SessionOutcome(spec, folder, cached=_is_complete(folder))
    if outcome.cached:
        _load_costs(outcome)
    else:
        log = log_dir / f"record-{spec.key}.log"
        outcome.record = run_measured(
            _record_command(spec, folder, views), log, cwd=TOOLS_DIR, timeout_s=SESSION_TIMEOUT_S
        )
        if outcome.record.returncode != 0 or not _is_complete(folder):
            outcome.error = f"recording failed: {_log_tail(log)} (log: {log})"
            return outcome
        outcome.record_s = outcome.record.wall_s
    if not _has_poses(folder):
        log = log_dir / f"poses-{spec.key}.log"
        command = python_command(
            "-m",
            "benchlib.poses_step",
            "--session",
            str(folder),
            "--bins",
            str(BINS),
            "--source",
            poses,
        )
        outcome.poses = run_measured(command, log, cwd=TOOLS_DIR, timeout_s=SESSION_TIMEOUT_S)
        reported = re.search(r"poses \(\w+, b=\d+\): ([\d.]+) s", log.read_text(errors="replace"))
        if outcome.poses.returncode != 0 or reported is None:
            outcome.error = f"poses failed: {_log_tail(log)} (log: {log})"
            return outcome
        outcome.poses_s = float(reported.group(1))
    _save_costs(outcome)
    _measure(outcome)
    return outcome


def _measure(outcome: SessionOutcome) -> None:
    """Counts of the session and how far its poses are from the truth."""
    with Session.open(outcome.folder) as session:
        outcome.frames, outcome.events = session.frame_count, session.event_count
        poses, split_us = session.poses(BINS), session.bins(BINS).split_us
    outcome.registered, outcome.latent = int(poses.registered.sum()), poses.registered.size
    if outcome.registered >= 3:
        errors = compare_with_truth(poses, split_us, load_truth(outcome.folder))
        outcome.rotation_error_deg = errors.median_rotation_deg
        outcome.centre_error = errors.median_translation_fraction
