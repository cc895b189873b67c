"""``seecap render``: render a fitted run at chosen exposures along a camera path."""

from __future__ import annotations

import argparse
from pathlib import Path

from davis_io.session import seconds_argument

__all__ = ["HELP", "add_arguments", "run"]

HELP = "render a fitted run: HDR EXR + LDR PNGs at chosen exposures, held-out views or a path"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the verb's arguments."""
    parser.add_argument("run_dir", type=Path, metavar="RUN", help="run folder session/fit/<run>")
    parser.add_argument(
        "--exposure",
        type=seconds_argument("--exposure"),
        nargs="+",
        default=(),
        metavar="SECONDS",
        help="LDR exposures: seconds (0.01), 10ms or 10000us (default: the five of the bracket)",
    )
    parser.add_argument(
        "--path",
        default=None,
        metavar="FILE|orbit",
        help="camera path: orbit, a transforms.json or a .npy of (N, 4, 4) OpenCV "
        "poses (default: the held-out views)",
    )
    parser.add_argument(
        "--out",
        default=None,
        help="name of an output folder inside the run (default: held-out, or path with "
        "--path); the fit's own renders/ are never overwritten",
    )
    parser.add_argument(
        "--video",
        type=Path,
        metavar="FILE.mp4",
        help="also write the views as an MP4 video: at the one --exposure given, or "
        "tone-mapped HDR without one (--path orbit makes a turn around the scene)",
    )
    parser.add_argument(
        "--undistorted",
        action="store_true",
        help="render through a pinhole of the camera's intrinsics instead of its lens "
        "(straight lines straight; the same without lens distortion)",
    )


def run(args: argparse.Namespace) -> int:
    """Render; print where; return 0."""
    from seenerf.train import render_run

    out = render_run(
        args.run_dir, tuple(args.exposure), args.path, args.out, args.video, args.undistorted
    )
    print(f"renders: {out}")
    if args.video is not None:
        print(f"video: {args.video}")
    return 0
