"""``seecap eval``: score a fitted run's held-out views against the session's truth."""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["HELP", "add_arguments", "run"]

HELP = "score a fitted run: HDR and novel-exposure PSNR / SSIM against the truth"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the verb's arguments."""
    parser.add_argument("run_dir", type=Path, metavar="RUN", help="run folder session/fit/<run>")


def run(args: argparse.Namespace) -> int:
    """Score; print; return 0."""
    from seenerf.eval.scores import format_scores
    from seenerf.train import evaluate_run

    print(format_scores(evaluate_run(args.run_dir)))
    return 0
