"""Lens benchmark: one scene through an undistorted and a distorted lens, the lens known, estimated
or ignored.

    python tools/bench_lens.py [--out bench-out/lens] [--budget 10m] [--publish]

Records the scene twice with one seed (as ``seecap record --emulate`` does, the second with ``--lens
random``), then fits four sessions with ``seecap fit --preset fast`` on one thread each, two side by
side: the undistorted session, and three copies of the distorted one (its DV calibration file given,
nothing given, its intrinsics given without the distortion). Each row: the lens the poses used,
their rotation error against the truth, the fit's scores. Writes ``OUT/lens.json`` and
``OUT/lens.md``; ``--publish`` copies the JSON to ``bench-results/`` and splices the report into
BENCHMARKS.md between its lens markers. About 30 minutes on 2 cores at a 10-minute budget.
"""

from __future__ import annotations

import json
import shutil
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from benchlib.lens import LENS_CASES, lens_report
from benchlib.machine import scene_header
from benchlib.publish import keep_report, report_folder, report_parser
from benchlib.runner import python_command, run_measured

from davis_io.capture import CaptureRequest, record_capture
from davis_io.emulator import EmulatedCamera
from davis_io.lens import write_camera_calibration
from davis_io.poses.truth import compare_with_truth
from davis_io.session import DEFAULT_BINS, Session

SCENE, SEED, FRAMES = "room", 7, 16
RUN = "lens"
TIMEOUT_S = 3600.0


def _seecap(*arguments: str) -> list[str]:
    return python_command("-m", "davis_io.cli", *arguments)


def _record(out: Path, name: str, lens: str) -> Path:
    folder = out / "sessions" / name
    if not (folder / "truth").is_dir():
        request = CaptureRequest(emulate=SCENE, seed=SEED, frames=FRAMES, lens=lens)
        record_capture(request, folder, overwrite=True)
    return folder


def _calibration_files(distorted: Path, out: Path) -> dict[str, Path]:
    """The lens as a DV calibration file, and its intrinsics alone as JSON."""
    lens = EmulatedCamera.of_session(distorted).config.optics
    known = write_camera_calibration(lens, out / "camera.xml", "DAVIS346_00000001")
    intrinsics = dict(zip(("fx", "fy", "cx", "cy"), lens.intrinsics.tolist(), strict=True))
    ignored = out / "intrinsics.json"
    ignored.write_text(json.dumps(intrinsics))
    return {"known": known, "ignored": ignored}


def _fit(name: str, session: Path, calibration: Path | None, budget: str, out: Path) -> dict:
    argv = ["fit", str(session), "--preset", "fast", "--time-budget", budget, "--threads", "1"]
    argv += ["--run", RUN, "--fresh"]
    if calibration is not None:
        argv += ["--camera-calibration", str(calibration)]
    usage = run_measured(_seecap(*argv), out / "logs" / f"fit-{name}.log", timeout_s=TIMEOUT_S)
    if usage.returncode != 0:
        return {"error": f"seecap fit exited {usage.returncode}; see logs/fit-{name}.log"}
    metrics = json.loads((session / "fit" / RUN / "metrics.json").read_text())
    with Session.open(session) as opened:
        poses = opened.poses(DEFAULT_BINS)
        errors = compare_with_truth(poses, opened.bins(DEFAULT_BINS).split_us, opened.truth())
    return {
        "intrinsics": poses.intrinsics.tolist(),
        "distortion": np.asarray(poses.distortion).tolist(),
        "rotation_deg_median": float(np.median(errors.rotation_deg)),
        "rotation_deg_max": float(np.max(errors.rotation_deg)),
        "hdr_psnr": metrics["hdr"]["psnr"],
        "novel_psnr": metrics["novel_exposure"]["psnr"],
        "steps": metrics["training"]["steps"],
        "wall_s": usage.wall_s,
    }


def main(argv: list[str] | None = None) -> int:
    parser = report_parser(__doc__.splitlines()[0], "bench-out/lens")
    parser.add_argument("--budget", default="10m", help="each fit's --time-budget")
    args = parser.parse_args(argv)
    out = report_folder(args.out)
    fit = f"seecap fit SESSION --preset fast --time-budget {args.budget} --threads 1"
    document = scene_header(SCENE, SEED, FRAMES, fit)
    pinhole = _record(out, "pinhole", "pinhole")
    distorted = _record(out, "distorted", "random")
    document["true_lens"] = EmulatedCamera.of_session(distorted).config.optics.to_json()
    files = _calibration_files(distorted, out)
    sessions = {"pinhole": pinhole}
    for name in ("known", "estimated", "ignored"):
        sessions[name] = out / "sessions" / name
        shutil.rmtree(sessions[name], ignore_errors=True)
        shutil.copytree(distorted, sessions[name])
    with ThreadPoolExecutor(2) as pool:
        futures = {
            name: pool.submit(_fit, name, sessions[name], files.get(name), args.budget, out)
            for name in LENS_CASES
        }
        document["cases"] = {name: future.result() for name, future in futures.items()}
    keep_report(out, "lens", document, lens_report(document), args.publish)
    return 1 if any("error" in case for case in document["cases"].values()) else 0


if __name__ == "__main__":
    sys.exit(main())
