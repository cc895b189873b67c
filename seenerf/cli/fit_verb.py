"""``seecap fit``: poses if missing, See-NeRF training, renders and scores of a session."""

from __future__ import annotations

import argparse
from pathlib import Path

from davis_io.session import parse_duration_us
from seenerf.errors import ConfigError

__all__ = ["HELP", "add_arguments", "parse_budget_s", "run"]

HELP = "fit See-NeRF to a session (poses if missing): sharp HDR renders, LDR brackets, scores"


def parse_budget_s(text: str) -> float:
    """Seconds of a budget: ``10m``, ``1.5h``, ``90s``, ``90`` (see ``parse_duration_us``).

    Raises:
        UsageError: not a positive duration.
    """
    return parse_duration_us(text, what="--time-budget") / 1e6


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the verb's arguments."""
    parser.add_argument("session", type=Path, help="session folder")
    parser.add_argument(
        "--preset",
        default="fast",
        help="training preset: fast (default), balanced, or paper (the published 8x256 MLP)",
    )
    parser.add_argument(
        "--variant",
        default="full",
        help="model variant: full (default) or a "
        "comparison (no-events, base, oracle, ...; an unknown name lists them)",
    )
    parser.add_argument(
        "--time-budget",
        type=parse_budget_s,
        default=0.0,
        metavar="DURATION",
        help="stop training after this long, poses included (10m, 600s)",
    )
    parser.add_argument("--steps", type=int, default=0, help="training steps (default: preset's)")
    parser.add_argument("--device", default="auto", help="auto (CUDA when present), cpu or cuda")
    parser.add_argument(
        "--bins", type=int, default=0, help="event bins per exposure b (default: the session's)"
    )
    parser.add_argument(
        "--subframes",
        type=int,
        default=1,
        help="poses per event bin in the blur integral, interpolated between the latent poses "
        "(default 1: the b+1 latent poses, as published); for motion of many pixels per bin",
    )
    parser.add_argument(
        "--low-pass",
        default="reference",
        help="delay filter reading: reference "
        "(first order on log radiance) or paper (second order on radiance)",
    )
    parser.add_argument(
        "--threshold",
        type=float,
        default=0.3,
        help="effective DVS contrast threshold in log units (default 0.3, the reference's); "
        "raise it when the sensor's events undercount contrast (refractory period, low "
        "bandwidth in the dark)",
    )
    parser.add_argument("--run", default=None, help="run folder name under session/fit/")
    parser.add_argument("--fresh", action="store_true", help="start over instead of resuming")
    parser.add_argument("--seed", type=int, default=0, help="random seed")
    parser.add_argument("--threads", type=int, default=0, help="CPU threads (default: torch's)")
    parser.add_argument(
        "--no-registration",
        action="store_true",
        help="score held-out views at their similarity-mapped poses without refining them",
    )


def run(args: argparse.Namespace) -> int:
    """Fit, print the scores; return 0."""
    from seenerf.eval.scores import format_scores
    from seenerf.model.config import FitConfig
    from seenerf.train.fit import fit_session

    if args.steps < 0:
        raise ConfigError("--steps must be >= 0")
    config = FitConfig(
        preset=args.preset,
        variant=args.variant,
        steps=args.steps,
        time_budget_s=args.time_budget,
        device=args.device,
        bins=args.bins,
        subframes=args.subframes,
        low_pass=args.low_pass,
        threshold=args.threshold,
        seed=args.seed,
        threads=args.threads,
        register_test_views=not args.no_registration,
    )
    result = fit_session(args.session, config, run_name=args.run, fresh=args.fresh)
    print(f"run: {result.run_dir}")
    print(format_scores(result.metrics))
    return 0
