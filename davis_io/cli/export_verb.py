"""``seecap export``: write a session's recorded data to another format (AEDAT 4.0)."""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["HELP", "add_arguments", "run"]

HELP = "export a session's events, frames, IMU and triggers to an AEDAT 4.0 file"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the options of ``seecap export``."""
    parser.add_argument("session", type=Path, help="session folder")
    parser.add_argument(
        "--aedat4",
        type=Path,
        required=True,
        metavar="FILE",
        help="AEDAT 4.0 file to write (opens in DV and dv-processing)",
    )


def run(args: argparse.Namespace) -> int:
    """Export and print where the file went."""
    from davis_io.session.export import export_aedat4

    path = export_aedat4(args.session, args.aedat4)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.1f} MB)")
    return 0
