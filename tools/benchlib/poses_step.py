"""Give a benchmark session poses and its calibration before any fit: poses estimated (the real
pipeline, calibration first) or the truth's.

python -m benchlib.poses_step --session DIR --bins 4 --source estimated|truth
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from davis_io.session import DEFAULT_BINS

__all__ = ["POSE_SOURCES", "main", "resolve_pose_source"]

POSE_SOURCES = ("estimated", "truth")
"""``estimated``: event-guided COLMAP as ``seecap fit`` runs it; ``truth``: the emulator's path."""


def resolve_pose_source(requested: str, quick: bool) -> str:
    """The pose source ``auto`` stands for, or ``requested`` itself.

    ``auto`` is ``truth`` in quick mode (4 training views are too few for structure from
    motion: the estimator registered 2 of 20 latent poses of the quick room session) and when
    ``davis_io.poses.estimate_poses`` is missing; otherwise ``estimated``. The report names the
    source used, so a benchmark on true poses is never mistaken for one on estimated poses.
    """
    if requested != "auto":
        return requested
    if quick:
        return "truth"
    try:
        from davis_io.poses import estimate_poses  # noqa: F401
    except ImportError:
        return "truth"
    return "estimated"


def main(argv: list[str] | None = None) -> int:
    """Store poses for ``--bins``; print the seconds spent; calibrate the sensor if not yet."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--session", type=Path, required=True, help="session folder")
    parser.add_argument("--bins", type=int, default=DEFAULT_BINS, help="event bins per exposure b")
    parser.add_argument("--source", choices=POSE_SOURCES, default="estimated")
    args = parser.parse_args(argv)
    from davis_io.prepare import prepare_session

    start = time.perf_counter()
    if args.source == "truth":
        from davis_io.poses.truth import store_true_poses

        store_true_poses(args.session, args.bins)
        spent_s = time.perf_counter() - start
        # Every fit then finds the sensor measured: fits side by side never race to measure it.
        prepare_session(args.session, args.bins, print)
    else:
        prepare_session(args.session, args.bins, print)  # calibration, then poses, as a fit does
        spent_s = time.perf_counter() - start
    print(f"poses ({args.source}, b={args.bins}): {spent_s:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
