"""Record an emulated session at a chosen exposure with a fixed sensor gain and scaled DVS noise.

Table 4 of the paper changes the input exposure at a fixed gain (shorter is darker, longer
clips) and the event noise level; the emulator's ``gain_exposure_us`` and ``noise_scale`` set
both:

    python -m benchlib.bracket_session --out DIR --exposure-us 256000 --gain-exposure-us 16000
                                       [--noise-scale 2] [--scene room] [--seed 1]
                                       [--frames 16] [--test-views 8]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from davis_io.emulator import EmulatedCamera
from davis_io.session.recorder import record
from davis_io.session.truth import save_truth

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """Record the session and its ``truth/``; print one summary line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True, help="session folder (replaced)")
    parser.add_argument("--exposure-us", type=int, required=True, help="APS exposure, µs")
    parser.add_argument(
        "--gain-exposure-us",
        type=int,
        default=0,
        help="exposure that sets the gain, µs (0: the exposure itself)",
    )
    parser.add_argument("--noise-scale", type=float, default=1.0, help="DVS noise multiplier")
    parser.add_argument("--scene", default="room", help="built-in scene")
    parser.add_argument("--seed", type=int, default=1, help="emulator seed")
    parser.add_argument("--frames", type=int, default=16, help="training views")
    parser.add_argument("--test-views", type=int, default=8, help="held-out views")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    camera = EmulatedCamera(
        args.scene,
        seed=args.seed,
        exposure_us=args.exposure_us,
        gain_exposure_us=args.gain_exposure_us,
        noise_scale=args.noise_scale,
        frames=args.frames,
        test_views=args.test_views,
    )
    result = record(camera, args.out, overwrite=True, exposure_us=args.exposure_us)
    save_truth(camera.truth, args.out / "truth")
    manifest = result.manifest
    print(
        f"{args.out}: {result.status}, {manifest.frame_count} frames, {manifest.event_count} "
        f"events in {time.perf_counter() - start:.1f} s"
    )
    return 0 if result.status == "complete" else 1


if __name__ == "__main__":
    sys.exit(main())
