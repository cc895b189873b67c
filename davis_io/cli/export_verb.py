"""``seecap export``: a session's recording as AEDAT 4.0, or its latent frames for nerfstudio."""

from __future__ import annotations

import argparse
from pathlib import Path

from davis_io.session.defaults import BINS, DEFAULT_BINS

__all__ = ["HELP", "add_arguments", "run"]

HELP = "export a session: its recording to AEDAT 4.0, or its sharp latent frames for nerfstudio"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the options of ``seecap export``."""
    parser.add_argument("session", type=Path, help="session folder")
    target = parser.add_mutually_exclusive_group(required=True)
    target.add_argument(
        "--aedat4",
        type=Path,
        metavar="FILE",
        help="AEDAT 4.0 file of the events, frames, IMU and triggers (opens in DV and "
        "dv-processing)",
    )
    target.add_argument(
        "--nerfstudio",
        type=Path,
        metavar="DIR",
        help="folder of the EDI latent frames COLMAP registered and a transforms.json (OpenCV "
        "model, OpenGL axes, pixel centres at +0.5) that nerfstudio and instant-ngp read",
    )
    parser.add_argument(
        "--bins",
        type=BINS.argument("--bins"),
        default=DEFAULT_BINS,
        help="with --nerfstudio: the poses' b",
    )


def run(args: argparse.Namespace) -> int:
    """Export and print where it went."""
    if args.aedat4 is not None:
        from davis_io.aedat.session_export import export_aedat4

        path = export_aedat4(args.session, args.aedat4)
        print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)")
        return 0
    from davis_io.poses.nerfstudio import export_nerfstudio

    path = export_nerfstudio(args.session, args.nerfstudio, args.bins)
    print(f"wrote {path} and {path.parent / 'images'}")
    return 0
