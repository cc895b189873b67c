"""``seecap fit``: calibration and poses if missing, See-NeRF training, renders and scores."""

from __future__ import annotations

import argparse
from pathlib import Path

from davis_io.session import seconds_argument
from seenerf.cli.options import add_dataclass_options, dataclass_values
from seenerf.model.config import FitConfig

__all__ = ["FLAGS", "HELP", "add_arguments", "run"]

HELP = (
    "fit See-NeRF to a session (sensor calibration and poses if missing): sharp HDR renders, "
    "LDR brackets, scores"
)

FLAGS = {"register_test_views": "--no-registration"}
"""Option strings that differ from the ones derived from :class:`FitConfig`'s field names."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the verb's arguments: session and run, then one option per :class:`FitConfig` field."""
    parser.add_argument("session", type=Path, help="session folder")
    parser.add_argument("--run", default=None, help="run folder name under session/fit/")
    parser.add_argument("--fresh", action="store_true", help="start over instead of resuming")
    add_dataclass_options(parser, FitConfig, seconds=seconds_argument("--time-budget"), flags=FLAGS)


def run(args: argparse.Namespace) -> int:
    """Calibrate and estimate poses when missing, fit, print the scores; return 0."""
    from davis_io.prepare import prepare_session
    from seenerf.eval.scores import format_scores
    from seenerf.train import fit_session
    from seenerf.train.fit import session_bins

    config = FitConfig(**dataclass_values(FitConfig, args)).validate()
    spent_s = prepare_session(args.session, session_bins(args.session, config))
    result = fit_session(args.session, config, run_name=args.run, fresh=args.fresh, spent_s=spent_s)
    print(f"run: {result.run_dir}")
    print(format_scores(result.metrics))
    return 0
