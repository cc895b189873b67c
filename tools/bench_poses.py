"""Benchmark: event-guided COLMAP poses on an emulated session, time per stage and pose error.

    python tools/bench_poses.py [--quick] [--views 16] [--bins 4] [--out DIR] [--unknown-intrinsics]

Records an emulated ``room`` session (346 x 260, 150 ms exposure, noisy DVS, RGGB) with its
truth, estimates the poses of all ``views x (bins + 1)`` latent frames, and prints the time of
every stage, the registration rate and the pose errors after the similarity alignment to the
truth. The target (:data:`benchlib.targets.POSES_S`) is for 16 views x 5 latent frames.
``--quick`` uses 6 views.
Other tools call :func:`run`, which returns the printed numbers as a dict.
"""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import sys
import tempfile
import time
from pathlib import Path

from benchlib.targets import POSES_S

from davis_io.capture import CaptureRequest, record_capture
from davis_io.emulator import EmulatedCamera
from davis_io.poses import estimate_poses
from davis_io.poses.truth import compare_with_truth
from davis_io.session import DEFAULT_BINS, Session
from davis_io.session.truth import load_truth


def run(
    quick: bool,
    *,
    views: int = 16,
    bins: int = DEFAULT_BINS,
    out: Path | None = None,
    unknown_intrinsics: bool = False,
) -> dict:
    """Record a session, estimate its poses, score them; return the numbers ``main`` prints.

    Args:
        quick: 6 views instead of ``views``.
        views: training views of the session.
        bins: event bins per exposure b.
        out: keep the session under this folder (default: a temporary one).
        unknown_intrinsics: let COLMAP estimate the focal length.

    Returns:
        ``machine``, ``views``, ``bins``, ``recording_s`` (the emulator, not part of the
        target), ``stages`` (stage name -> seconds), ``summary`` (the estimator's report),
        ``total_s``, ``target_s``, ``median_rotation_deg`` and ``median_translation_fraction``
        (centre error over the scene extent).
    """
    views = 6 if quick else views
    with tempfile.TemporaryDirectory() as temporary:
        folder = (out or Path(temporary)) / f"room{views}"
        started = time.perf_counter()
        request = CaptureRequest(emulate="room", frames=views)
        record_capture(request, folder, bins=bins, overwrite=True)
        recording_s = time.perf_counter() - started
        lens = None if unknown_intrinsics else EmulatedCamera.of_session(folder).config.optics
        stages: dict[str, float] = {}
        clock = {"stage": None, "at": time.perf_counter()}

        def progress(stage: str, _done: int, _total: int) -> None:
            now = time.perf_counter()
            if stage != clock["stage"]:
                if clock["stage"] is not None:
                    stages[clock["stage"]] = stages.get(clock["stage"], 0) + now - clock["at"]
                clock.update(stage=stage, at=now)

        started = time.perf_counter()
        report = estimate_poses(folder, b=bins, lens=lens, force=True, progress=progress)
        total = time.perf_counter() - started
        progress("done", 0, 0)
        with Session.open(folder) as session:
            errors = compare_with_truth(
                session.poses(bins),
                session.bins(bins).split_us,
                load_truth(session.truth_dir),
            )
    return {
        "machine": f"{platform.platform()}, {os.cpu_count()} CPUs, {platform.processor() or '?'}",
        "views": views,
        "bins": bins,
        "recording_s": recording_s,
        "stages": stages,
        "summary": report.summary(),
        "total_s": total,
        "target_s": POSES_S.limit,
        "median_rotation_deg": errors.median_rotation_deg,
        "median_translation_fraction": errors.median_translation_fraction,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="6 views instead of 16")
    parser.add_argument("--views", type=int, default=16)
    parser.add_argument("--bins", type=int, default=DEFAULT_BINS)
    parser.add_argument("--out", type=Path, help="keep the session here (default: temporary)")
    parser.add_argument(
        "--unknown-intrinsics", action="store_true", help="let COLMAP estimate the focal length"
    )
    args = parser.parse_args()
    print("command:", shlex.join([Path(sys.executable).name, *sys.argv]))
    result = run(
        args.quick,
        views=args.views,
        bins=args.bins,
        out=args.out,
        unknown_intrinsics=args.unknown_intrinsics,
    )
    print(f"machine: {result['machine']}")
    print(f"recording (emulator, not part of the target): {result['recording_s']:.1f} s")
    for stage, seconds in result["stages"].items():
        print(f"  {stage:32s} {seconds:6.1f} s")
    print(result["summary"])
    total, views, bins = result["total_s"], result["views"], result["bins"]
    print(
        f"pose estimation: {total:.1f} s for {views} views x {bins + 1} latent frames "
        f"(target {POSES_S.goal} s for 16 x 5: {'met' if POSES_S.met(total) else 'MISSED'})"
    )
    print(
        f"median rotation error {result['median_rotation_deg']:.3f} deg, median translation "
        f"error {100 * result['median_translation_fraction']:.2f} % of the scene extent"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
