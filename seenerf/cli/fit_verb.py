"""``seecap fit``: poses if missing, See-NeRF training, renders and scores of a session."""

from __future__ import annotations

import argparse
from pathlib import Path

from davis_io.errors import UsageError
from davis_io.session import parse_duration_us

__all__ = ["HELP", "add_arguments", "parse_budget_s", "run"]

HELP = "fit See-NeRF to a session (poses if missing): sharp HDR renders, LDR brackets, scores"


def parse_budget_s(text: str) -> float:
    """Seconds of a budget: ``10m``, ``1.5h``, ``90s``, ``90`` (see ``parse_duration_us``).

    Raises:
        UsageError: not a positive duration.
    """
    return parse_duration_us(text, what="--time-budget") / 1e6


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the verb's arguments."""
    parser.add_argument("session", type=Path, help="session folder")
    parser.add_argument(
        "--preset",
        default="fast",
        help="training preset: fast (default), balanced, or paper (the published 8x256 MLP)",
    )
    parser.add_argument(
        "--variant",
        default="full",
        help="model variant: full (default) or a "
        "comparison (no-events, base, oracle, ...; an unknown name lists them)",
    )
    parser.add_argument(
        "--time-budget",
        type=parse_budget_s,
        default=0.0,
        metavar="DURATION",
        help="stop training after this long, poses included (10m, 600s)",
    )
    parser.add_argument("--steps", type=int, default=0, help="training steps (default: preset's)")
    parser.add_argument("--device", default="auto", help="auto (CUDA when present), cpu or cuda")
    parser.add_argument(
        "--bins", type=int, default=0, help="event bins per exposure b (default: the session's)"
    )
    parser.add_argument(
        "--subframes",
        type=int,
        default=1,
        help="poses per event bin in the blur integral, interpolated between the latent poses "
        "(default 1: the b+1 latent poses, as published); for motion of many pixels per bin",
    )
    parser.add_argument(
        "--low-pass",
        default="reference",
        help="delay filter reading: reference "
        "(first order on log radiance) or paper (second order on radiance)",
    )
    parser.add_argument(
        "--threshold",
        type=float,
        default=0.3,
        help="effective DVS contrast threshold in log units (default 0.3, the reference's); "
        "raise it when the sensor's events undercount contrast (refractory period, low "
        "bandwidth in the dark)",
    )
    parser.add_argument("--run", default=None, help="run folder name under session/fit/")
    parser.add_argument("--fresh", action="store_true", help="start over instead of resuming")
    parser.add_argument("--seed", type=int, default=0, help="random seed")
    parser.add_argument("--threads", type=int, default=0, help="CPU threads (default: torch's)")
    parser.add_argument(
        "--no-registration",
        action="store_true",
        help="score held-out views at their similarity-mapped poses without refining them",
    )


def run(args: argparse.Namespace) -> int:
    """Fit, print the scores; return 0."""
    from seenerf.config import FitConfig
    from seenerf.fit import fit_session

    if args.steps < 0:
        raise UsageError("--steps must be >= 0")
    config = FitConfig(
        preset=args.preset,
        variant=args.variant,
        steps=args.steps,
        time_budget_s=args.time_budget,
        device=args.device,
        bins=args.bins,
        subframes=args.subframes,
        low_pass=args.low_pass,
        threshold=args.threshold,
        seed=args.seed,
        threads=args.threads,
        register_test_views=not args.no_registration,
    )
    result = fit_session(args.session, config, run_name=args.run, fresh=args.fresh)
    print(f"run: {result.run_dir}")
    print(format_scores(result.metrics))
    return 0


def format_scores(metrics: dict) -> str:
    """One line per score of a ``metrics.json`` payload (the shared printout of fit and eval)."""
    lines = []
    if "hdr" in metrics:
        lines.append(
            f"HDR (tone-mapped, scale-aligned): PSNR {metrics['hdr']['psnr']:.2f} dB  "
            f"SSIM {metrics['hdr']['ssim']:.4f}"
        )
        lines.append(
            f"HDR (tone-mapped, unaligned):     PSNR {metrics['hdr_unaligned']['psnr']:.2f} dB"
        )
        novel = metrics["novel_exposure"]
        lines.append(
            f"novel exposures (2nd, 4th):       PSNR {novel['psnr']:.2f} dB  "
            f"SSIM {novel['ssim']:.4f}"
        )
        for exposure, score in metrics.get("ldr", {}).items():
            lpips = f"  LPIPS {score['lpips']:.4f}" if "lpips" in score else ""
            lines.append(
                f"  LDR {exposure:>8} s: PSNR {score['psnr']:.2f} dB  SSIM {score['ssim']:.4f}"
                + lpips
            )
        if "lpips" in metrics:
            lines.append(metrics["lpips"])
        if "residual_blur" in metrics:
            blur = metrics["residual_blur"]
            lines.append(
                f"sharpness: the middle exposure's views match the truth blurred by "
                f"{blur['sigma_px']:.3g} px (Gaussian sigma; {blur['psnr_gain']:+.2f} dB against "
                "the unblurred truth)"
            )
        poses = metrics.get("test_poses", {})
        if poses.get("registered"):
            mapped = poses["at_mapped_poses"]
            lines.append(
                f"held-out poses registered to the model (turned {poses['turned_deg_median']:.2f} "
                f"deg median); at the mapped poses: HDR {mapped['hdr_psnr']:.2f} dB, "
                f"novel {mapped['novel_exposure_psnr']:.2f} dB"
            )
    else:
        lines.append("no ground truth: renders written, nothing scored")
    lines.append(f"render: {metrics.get('render_s_per_view', float('nan')):.2f} s per view")
    return "\n".join(lines)
