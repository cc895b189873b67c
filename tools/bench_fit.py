"""Benchmark of See-NeRF fits: quality per variant on emulated sessions, and speed per preset.

Examples:
    python tools/bench_fit.py --quick
    python tools/bench_fit.py --scene room --budget 600 --variants full,no-events,base,oracle

The full mode records an emulated session (as ``seecap record --emulate`` does) unless ``--session``
is given, estimates poses through ``seecap fit`` (or, with ``--true-poses``, stores the truth's
poses when the pose estimator is unavailable: the report says so), fits each variant with the same
time budget, and prints HDR and novel-exposure scores beside the training speed.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import torch

from davis_io.capture import CaptureRequest, record_capture
from davis_io.poses.truth import store_true_poses
from davis_io.prepare import prepare_session
from davis_io.session import DEFAULT_BINS
from davis_io.session.units import parse_duration_us
from seenerf.data.session import load_training_data
from seenerf.data.synthetic import plane_scene
from seenerf.model.config import DEFAULT_VARIANT, FitConfig
from seenerf.model.presets import DEFAULT_PRESET
from seenerf.train.fit import fit_data
from seenerf.train.methods import make_method
from seenerf.train.session_fit import training_data
from seenerf.train.trainer import Trainer


def machine() -> str:
    return (
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, torch "
        f"{torch.__version__}, {torch.get_num_threads()} threads, "
        f"cuda={'yes' if torch.cuda.is_available() else 'no'}"
    )


SPEED_BATCH_PIXELS = {"fast": None, "balanced": None, "paper": 32}
"""Blurry pixels per step of each preset in the speed table: the CPU presets' own batch (None),
a smaller one for the paper preset, whose MLP at its published 1,024 holds over 13 GB here."""


def speed_trainer(data, preset: str) -> Trainer:
    """A trainer of ``preset`` without CRF warm start or held-out pixels, for timing steps."""
    config = FitConfig.of(
        preset=preset,
        steps=1,
        batch_pixels=SPEED_BATCH_PIXELS[preset],
        warm_steps=0,
        validation_share=0.0,
    )
    return Trainer(make_method(data, config), log=lambda line: None)


def warm_up_steps(trainer: Trainer) -> int:
    """Untimed steps before timing: two, and for an occupancy-grid sampler two grid refreshes,
    so the timed steps skip empty space as a fit's steps do after its first seconds."""
    if trainer.model.renderer.grid is None:
        return 2
    return 2 * trainer.preset.grid_every


def timed_steps(trainer: Trainer, steps: int) -> tuple[int, float]:
    """Train ``steps`` more steps; return the rays rendered and the seconds taken."""
    trainer.total_steps = trainer.summary.steps + steps
    start = time.perf_counter()
    trainer.train()
    rays_per_step = trainer.preset.pixels_per_step * (trainer.data.num_bins + 1)
    return steps * rays_per_step, time.perf_counter() - start


def speed_table(data, steps: int, rounds: int = 3) -> dict:
    """Rays per second of each preset on the same data, warmed up and timed side by side.

    Every preset first trains its :func:`warm_up_steps` untimed (allocator, thread pool,
    autograd and, for the CPU presets, a pruned occupancy grid). Then ``rounds`` rounds each
    time ``steps`` steps of every preset in turn (``steps // 10``, at least 1, for the paper
    preset), so machine load that changes during the run falls on all presets alike; the rate
    is the total rays over the total seconds of each preset.
    """
    trainers = {name: speed_trainer(data, name) for name in SPEED_BATCH_PIXELS}
    for trainer in trainers.values():
        timed_steps(trainer, warm_up_steps(trainer))
    totals = {name: [0, 0.0] for name in trainers}
    for _ in range(rounds):
        for name, trainer in trainers.items():
            rays, seconds = timed_steps(trainer, steps if name != "paper" else max(1, steps // 10))
            totals[name][0] += rays
            totals[name][1] += seconds
    table = {name: rays / max(seconds, 1e-9) for name, (rays, seconds) in totals.items()}
    table["fast_over_paper"] = table["fast"] / table["paper"]
    return table


def record(scene: str, out: Path, frames: int, exposure: str) -> float:
    """Record ``scene`` into ``out`` as ``seecap record --emulate`` does; seconds taken."""
    start = time.perf_counter()
    exposure_us = parse_duration_us(exposure, what="--exposure")
    record_capture(
        CaptureRequest(emulate=scene, exposure_us=exposure_us, frames=frames), out, overwrite=True
    )
    return time.perf_counter() - start


def quality(
    session_dir: Path, variants: list[str], preset: str, budget: float, b: int, true_poses: bool
) -> dict:
    start = time.perf_counter()
    try:
        prepare_session(session_dir, b, print)
        pose_source = "estimated"
    except Exception as error:  # the estimator is optional here: report and fall back
        if not true_poses:
            raise
        print(f"pose estimation unavailable ({error}); storing the truth's poses")
        store_true_poses(session_dir, b)
        pose_source = "truth"
    poses_s = time.perf_counter() - start
    results = {"pose_source": pose_source, "poses_s": poses_s}
    for variant in variants:
        config = FitConfig.of(preset=preset, variant=variant, time_budget_s=budget, steps=100_000)
        run = fit_data(
            training_data(session_dir, b, config),  # a white-box variant reads the truth's sensor
            config,
            session_dir / "fit" / f"bench-{preset}-{variant}",
            fresh=True,
            log=print,
            spent_s=poses_s if variant == DEFAULT_VARIANT else 0.0,
        )
        m = run.metrics
        results[variant] = {
            "hdr_psnr": m["hdr"]["psnr"],
            "hdr_ssim": m["hdr"]["ssim"],
            "hdr_psnr_unaligned": m["hdr_unaligned"]["psnr"],
            "novel_psnr": m["novel_exposure"]["psnr"],
            "novel_ssim": m["novel_exposure"]["ssim"],
            "steps": run.summary.steps,
            "train_s": run.summary.elapsed_s,
            "rays_per_s": run.summary.rays_per_s,
            "render_s_per_view": m["render_s_per_view"],
        }
        print(json.dumps({variant: results[variant]}))
    return results


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="synthetic plane scene, speed only")
    parser.add_argument("--scene", default="room")
    parser.add_argument(
        "--session", type=Path, help="use this emulated session instead of recording"
    )
    parser.add_argument("--out", type=Path, default=Path("bench-sessions"))
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--exposure", default="0.15")
    parser.add_argument("--bins", type=int, default=DEFAULT_BINS)
    parser.add_argument("--preset", default=DEFAULT_PRESET)
    parser.add_argument("--variants", default="full,no-events,base,oracle")
    parser.add_argument("--budget", type=float, default=600.0, help="seconds per variant")
    parser.add_argument(
        "--true-poses",
        action="store_true",
        help="store the truth's poses if the pose estimator is unavailable",
    )
    args = parser.parse_args()
    torch.set_num_threads(min(2, os.cpu_count() or 1))
    print(f"machine: {machine()}")
    print(f"command: {' '.join(sys.argv)}")
    if args.quick:
        data = plane_scene(height=64, width=86, frames=6)
        print(json.dumps({"rays_per_s": speed_table(data, steps=10)}, indent=1))
        return 0
    session = args.session
    if session is None:
        session = args.out / f"{args.scene}-{args.exposure}s"
        print(
            f"recorded {session} in {record(args.scene, session, args.frames, args.exposure):.0f} s"
        )
    results = quality(
        session, args.variants.split(","), args.preset, args.budget, args.bins, args.true_poses
    )
    results["rays_per_s"] = speed_table(load_training_data(session, args.bins), steps=10)
    print(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
