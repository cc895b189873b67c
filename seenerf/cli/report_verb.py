"""``seecap report``: a fitted run's page, ``RUN/report.html``, written again from its files."""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["HELP", "add_arguments", "run"]

HELP = "write a fitted run's report.html: inputs beside renders, an exposure slider, the sensor"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the verb's arguments."""
    parser.add_argument("run_dir", type=Path, metavar="RUN", help="run folder session/fit/<run>")


def run(args: argparse.Namespace) -> int:
    """Write the page; print where; return 0."""
    from seenerf.errors import CheckpointError
    from seenerf.eval.report import is_session_run, write_report

    if not is_session_run(args.run_dir):
        raise CheckpointError(
            f"{args.run_dir} is not a run folder of a session (SESSION/fit/RUN): give one that "
            "`seecap fit` wrote"
        )
    print(f"report: {write_report(args.run_dir)}")
    return 0
