"""Rays per second of every preset on one session, in one process (the trainer's own probe).

    python -m benchlib.speed_probe --session DIR [--bins 4] [--steps 10]

Prints one JSON line ``{"rays_per_s": {"fast": ..., "balanced": ..., "paper": ...,
"fast_over_paper": ...}}`` from ``tools/bench_fit.py``'s ``speed_table``: untimed warm-up steps
per preset, then timed rounds in turn on the same data, without CRF warm start or renders.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from davis_io.session import DEFAULT_BINS

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """Load the session's training data, time every preset, print the JSON line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--session", type=Path, required=True, help="session folder with poses")
    parser.add_argument("--bins", type=int, default=DEFAULT_BINS, help="event bins per exposure b")
    parser.add_argument("--steps", type=int, default=10, help="steps per preset (paper: 1/10)")
    args = parser.parse_args(argv)
    from bench_fit import speed_table

    from seenerf.data.session import load_training_data

    table = speed_table(load_training_data(args.session, args.bins), steps=args.steps)
    print(json.dumps({"rays_per_s": table}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
