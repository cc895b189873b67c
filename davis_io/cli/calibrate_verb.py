"""``seecap calibrate``: measure the sensor's thresholds, latency and response from a session."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["HELP", "add_arguments", "run"]

HELP = "measure the DVS thresholds, event latency and APS response from the recording itself"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the options of ``seecap calibrate``."""
    parser.add_argument("session", type=Path, help="session folder")
    parser.add_argument("--force", action="store_true", help="measure again even if stored")


def run(args: argparse.Namespace) -> int:
    """Measure (or read) the calibration and print it."""
    from davis_io.calibration.session_calibration import calibrate_session

    calibration = calibrate_session(
        args.session, force=args.force, progress=lambda line: print(line, file=sys.stderr)
    )
    print(calibration.summary())
    return 0
