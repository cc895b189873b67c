"""``seecap inspect``: summarise an AEDAT file, a raw USB dump or a session folder."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

__all__ = ["HELP", "add_arguments", "run"]

HELP = "summary of an AEDAT 2.0 / 3.1 / 4.0 file, a raw USB dump or a session folder"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the verb's arguments."""
    parser.add_argument("path", type=Path, help="recording file or session folder")
    parser.add_argument("--json", action="store_true", help="print machine-readable JSON")
    parser.add_argument(
        "--raw-usb",
        metavar="MODEL",
        help="PATH is a raw USB bulk-IN dump of camera MODEL (davis346, davis240)",
    )
    parser.add_argument(
        "--frames", action="store_true", help="session folders: add a per-frame table"
    )
    parser.add_argument(
        "--repair",
        action="store_true",
        help="session folders: repair a recording that never closed",
    )


def run(args: argparse.Namespace) -> int:
    """Print the summary; return 0."""
    from davis_io.summary import format_summary, summarize

    if args.path.is_dir():
        from davis_io.session.inspect import describe_session

        return describe_session(args.path, args)
    if args.raw_usb:
        from davis_io.usb.dump import open_raw_usb_dump

        source = open_raw_usb_dump(args.path, args.raw_usb)
    else:
        from davis_io.aedat import open_recording

        source = open_recording(args.path)
    with source:
        summary = summarize(source)
    print(json.dumps(summary.to_dict(), indent=2) if args.json else format_summary(summary))
    return 0
