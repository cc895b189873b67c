"""``seecap fit``: calibration and poses if missing, See-NeRF training, renders and scores."""

from __future__ import annotations

import argparse
import sys
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
    parser.add_argument(
        "--config",
        type=Path,
        metavar="CONFIG_JSON",
        help="fit again with the configuration a run saved (its config.json); the fit options "
        "below are then ignored",
    )
    parser.add_argument(
        "--quiet", action="store_true", help="no progress bar or lines: the result only"
    )
    add_dataclass_options(parser, FitConfig, seconds=seconds_argument("--time-budget"), flags=FLAGS)


class _TrainingBar:
    """A tqdm bar over the training budget (or steps), with steps/s; lines printed above it."""

    def __init__(self, quiet: bool):
        self.quiet, self.bar = quiet, None

    def line(self, text: str) -> None:
        if self.quiet:
            return
        if self.bar is None:
            print(text, flush=True)
        else:
            self.bar.write(text)

    def step(self, trainer) -> None:
        if self.quiet:
            return
        from tqdm import tqdm

        budget = trainer.config.time_budget_s - trainer.spent_s
        by_time = trainer.config.time_budget_s > 0
        if self.bar is None:
            total = round(budget) if by_time else trainer.total_steps
            unit = "s" if by_time else "step"
            # A log file gets a line every 30 s, not one per step.
            interval = 0.5 if sys.stderr.isatty() else 30.0
            self.bar = tqdm(
                total=total, unit=unit, desc="training", dynamic_ncols=True, mininterval=interval
            )
        done = (
            min(round(trainer.summary.elapsed_s), self.bar.total)
            if by_time
            else (trainer.summary.steps)
        )
        rate = trainer.summary.steps / max(trainer.summary.elapsed_s, 1e-9)
        self.bar.set_postfix_str(f"step {trainer.summary.steps}, {rate:.1f} steps/s", refresh=False)
        self.bar.update(done - self.bar.n)  # drawn at most once per interval

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def run(args: argparse.Namespace) -> int:
    """Calibrate and estimate poses when missing, fit, print the scores; return 0."""
    from davis_io.prepare import prepare_session
    from seenerf.eval.scores import format_scores
    from seenerf.model.config import load_config
    from seenerf.train import fit_session
    from seenerf.train.fit import session_bins

    if args.config is not None:
        config = load_config(args.config)
    else:
        config = FitConfig(**dataclass_values(FitConfig, args)).validate()
    bar = _TrainingBar(args.quiet)
    try:
        spent_s = prepare_session(args.session, session_bins(args.session, config), bar.line)
        result = fit_session(
            args.session,
            config,
            run_name=args.run,
            fresh=args.fresh,
            spent_s=spent_s,
            log=bar.line,
            on_step=bar.step,
        )
    finally:
        bar.close()
    print(f"run: {result.run_dir}")
    print(format_scores(result.metrics))
    return 0
