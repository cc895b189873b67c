"""``seecap doctor``: check libusb, camera permissions, udev rule, libraries, GPU and disk."""

from __future__ import annotations

import argparse
from pathlib import Path

from davis_io.usb.doctor import run_checks

__all__ = ["HELP", "add_arguments", "run"]

HELP = "check this machine: libusb, camera permissions, udev rule, pycolmap, torch, GPU, disk"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """``--path`` of the folder sessions will be written to."""
    parser.add_argument(
        "--path",
        type=Path,
        default=Path("."),
        help="folder where sessions will be written (free disk space)",
    )


def run(args: argparse.Namespace) -> int:
    """Print each check; exit 1 when any failed."""
    checks = run_checks(args.path)
    for check in checks:
        print(f"[{'ok' if check.ok else 'FAIL'}] {check.name}: {check.detail}")
    return 0 if all(check.ok for check in checks) else 1
