"""Record an emulated session at a chosen exposure with a fixed sensor gain and scaled DVS noise.

Table 4 of the paper changes the input exposure at a fixed gain (shorter is darker, longer
clips) and the event noise level. The emulator ties its gain to the frame's own exposure and
names DVS settings by preset, so this maker sets both for its own process only:

    python -m benchlib.bracket_session --out DIR --exposure-us 256000 --gain-exposure-us 16000
                                       [--noise-scale 2] [--scene room] [--seed 1]
                                       [--frames 16] [--test-views 8]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

from davis_io.emulator import DVS_PRESETS, EmulatedCamera, EmulatorConfig, save_truth
from davis_io.session.recorder import record

__all__ = ["FixedGainConfig", "bracket_camera", "main"]

BASE_DVS_PRESET = "noisy"
"""DVS preset of the benchmark sessions; noise x1 is this preset's leak and shot-noise rates."""


@dataclasses.dataclass(frozen=True)
class FixedGainConfig(EmulatorConfig):
    """Emulator settings whose sensor gain comes from ``gain_exposure_us``, not the exposure.

    Attributes:
        gain_exposure_us: exposure whose reciprocal is the gain (0: the frame's own exposure).
    """

    gain_exposure_us: int = 0

    @property
    def gain_per_s(self) -> float:
        """Sensor gain, 1 / s: response input = gain x radiance x exposure."""
        return 1e6 / (self.gain_exposure_us or self.exposure_us)


def _register_noise_preset(scale: float) -> str:
    """Name of the base DVS preset with leak and shot noise x ``scale``, registered if new."""
    if scale == 1.0:
        return BASE_DVS_PRESET
    base = DVS_PRESETS[BASE_DVS_PRESET]
    name = f"{BASE_DVS_PRESET}-x{scale:g}"
    DVS_PRESETS.setdefault(
        name,
        dataclasses.replace(
            base,
            leak_rate_hz=base.leak_rate_hz * scale,
            shot_noise_rate_hz=base.shot_noise_rate_hz * scale,
        ),
    )
    return name


def bracket_camera(
    scene: str,
    seed: int,
    exposure_us: int,
    gain_exposure_us: int,
    noise_scale: float,
    frames: int,
    test_views: int,
) -> EmulatedCamera:
    """An emulated DAVIS346 with the gain of ``gain_exposure_us`` and DVS noise x ``noise_scale``.

    The camera is built as usual, then given the equal :class:`FixedGainConfig` (same fields,
    so the same trajectory), which every later frame and the truth read.
    """
    camera = EmulatedCamera(
        scene,
        seed=seed,
        exposure_us=exposure_us,
        frames=frames,
        test_views=test_views,
        dvs_preset=_register_noise_preset(noise_scale),
    )
    fields = dataclasses.asdict(camera.config)
    camera.config = FixedGainConfig(**fields, gain_exposure_us=gain_exposure_us)
    camera.info.extra["emulator"].update(gain_exposure_us=gain_exposure_us, noise_scale=noise_scale)
    return camera


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
    camera = bracket_camera(
        args.scene,
        args.seed,
        args.exposure_us,
        args.gain_exposure_us,
        args.noise_scale,
        args.frames,
        args.test_views,
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
