"""``seecap poses``: camera poses of a session from event-deblurred frames and COLMAP."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from davis_io.session.defaults import BINS, DEFAULT_BINS, THRESHOLD

__all__ = ["HELP", "add_arguments", "run"]

HELP = "estimate camera poses (EDI latent frames + COLMAP) and store them in the session"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the options of ``seecap poses``."""
    parser.add_argument("session", type=Path, help="session folder")
    parser.add_argument(
        "--bins",
        type=BINS.argument("--bins"),
        default=DEFAULT_BINS,
        help="event bins per exposure (b)",
    )
    parser.add_argument(
        "--camera-calibration",
        "--intrinsics",
        type=Path,
        metavar="FILE",
        help="the camera's lens, held fixed: DV's or OpenCV's calibration (XML or YAML), "
        "COLMAP's cameras.txt, or JSON with fx, fy, cx, cy (pixel centres at integers) and "
        "optionally k1, k2, p1, p2, k3",
    )
    parser.add_argument(
        "--threshold",
        type=THRESHOLD.argument("--threshold"),
        help="DVS contrast threshold (log units per event)",
    )
    parser.add_argument("--force", action="store_true", help="estimate again even if stored")


class _StageBars:
    """One tqdm bar per stage, closed when the next stage starts."""

    def __init__(self):
        self.stage, self.bar = None, None

    def __call__(self, stage: str, done: int, total: int) -> None:
        from tqdm import tqdm

        if stage != self.stage:
            self.close()
            self.stage = stage
            interval = 0.5 if sys.stderr.isatty() else 30.0  # a log file: a line per 30 s
            self.bar = tqdm(total=total or None, desc=stage, unit="img", mininterval=interval)
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def run(args: argparse.Namespace) -> int:
    """Estimate the poses and print the report."""
    from davis_io.poses.estimate import estimate_poses, stated_lens

    calibration = args.camera_calibration
    lens = stated_lens(args.session, calibration) if calibration else None
    bars = _StageBars()
    try:
        report = estimate_poses(
            args.session,
            b=args.bins,
            lens=lens,
            force=args.force,
            progress=bars,
            threshold=args.threshold,
        )
    finally:
        bars.close()
    print(report.summary())
    return 0
