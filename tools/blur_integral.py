"""How closely the fit's blur model can reproduce an emulated session's frames, and the noise.

    python tools/blur_integral.py SESSION [--bins 4] [--subframes 1 4] [--frames 4]

A fit synthesises each blurry frame as the trapezoid sum of sharp images at its b+1 latent time
points (eq. 6), or at M poses per bin with ``seecap fit --subframes M``. For an emulated session
this renders that sum from the true scene at the true poses, noise-free and through the true
response, and compares it with the noise-free frame the emulator records (its sub-frames evenly
spaced over the exposure): the PSNR a perfect field could reach on the frames under that blur
model. It also compares the recorded frames with their noise-free rendering: the sensor noise a
field cannot fit. A blur model further from the frames than the noise pulls the field away from
the truth; PSNRs are of 10-bit values scaled to [0, 1], as the fit's held-out pixels are.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from davis_io.bins import subdivide, trapezoid_weights
from davis_io.emulator import EmulatedCamera
from davis_io.session import DEFAULT_BINS, Session
from seenerf.eval.metrics import psnr

ADC_TOP = 1023.0
"""Largest 10-bit ADC value: frames are compared scaled to [0, 1]."""


def blur_model_psnr(
    session_dir: Path, b: int, per_bin: tuple[int, ...], frames: int
) -> tuple[dict[int, float], float]:
    """Mean PSNR of the blur model per poses-per-bin count, and of the recorded frames.

    Args:
        session_dir: an emulated session with bins of ``b``.
        b: bins per exposure.
        per_bin: poses per bin in the trapezoid sum to try (1: the latent poses only).
        frames: exposures compared, spread over the session.

    Returns:
        ``{poses per bin: PSNR}`` of the model sum against the noise-free frame, and the PSNR of
        the recorded frames against it (the noise floor), dB.
    """
    with Session.open(session_dir) as session:
        split_us = session.bins(b).split_us
        chosen = np.linspace(0, session.frame_count - 1, frames).round().astype(int)
        recorded = [session.frame(int(i)) for i in chosen]
    camera = EmulatedCamera.of_session(session_dir)
    model, noise = {count: [] for count in per_bin}, []
    for index, frame in zip(chosen, recorded, strict=True):
        clean = camera.noise_free_frame(frame) / ADC_TOP
        noise.append(psnr(frame.image / ADC_TOP, clean))
        for count in per_bin:
            times = subdivide(split_us[index], count).round().astype(np.int64)
            summed = camera.expose_at(times, trapezoid_weights(times)) / ADC_TOP
            model[count].append(psnr(summed, clean))
    return {count: float(np.mean(v)) for count, v in model.items()}, float(np.mean(noise))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("session", type=Path, help="an emulated session folder")
    parser.add_argument("--bins", type=int, default=DEFAULT_BINS)
    parser.add_argument(
        "--subframes", type=int, nargs="+", default=[1, 4], help="poses per bin to try"
    )
    parser.add_argument("--frames", type=int, default=4, help="exposures to compare")
    args = parser.parse_args()
    model, noise = blur_model_psnr(args.session, args.bins, tuple(args.subframes), args.frames)
    for count, value in model.items():
        print(
            f"b = {args.bins}, {count} pose(s) per bin: the trapezoid sum of the true scene "
            f"matches the noise-free frames at {value:.2f} dB"
        )
    print(f"the recorded frames match them at {noise:.2f} dB (sensor noise)")


if __name__ == "__main__":
    main()
