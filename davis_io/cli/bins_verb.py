"""``seecap bins``: compute (or recompute) a session's event bins for another b."""

from __future__ import annotations

import argparse
from pathlib import Path

from davis_io.session.defaults import BINS

__all__ = ["HELP", "add_arguments", "run"]

HELP = "compute a session's exposure-synchronised event bins for another number of bins"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the options of ``seecap bins``."""
    parser.add_argument("session", type=Path, help="session folder")
    parser.add_argument(
        "--bins", type=BINS.argument("--bins"), required=True, help="event bins per exposure"
    )
    parser.add_argument("--force", action="store_true", help="recompute bins already stored")


def run(args: argparse.Namespace) -> int:
    """Compute the bins and print a short summary of them."""
    from davis_io.session.rebin import compute_session_bins

    summary = compute_session_bins(args.session, args.bins, force=args.force)
    print(summary)
    return 0
