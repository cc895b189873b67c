"""``seecap bench``: speed against error of every preset and variant, via ``tools/bench.py``."""

from __future__ import annotations

import argparse
import importlib.util
import shlex
import sys
from pathlib import Path

from davis_io.errors import UsageError

__all__ = ["HELP", "add_arguments", "bench_tool_path", "run"]

HELP = "benchmark every preset and variant: speed against error, the paper's tables, capture speed"


def bench_tool_path() -> Path:
    """``tools/bench.py`` of the source checkout this package runs from.

    Raises:
        UsageError: the package is not installed from a checkout (no ``tools/`` beside it).
    """
    path = Path(__file__).resolve().parents[2] / "tools" / "bench.py"
    if not path.exists():
        raise UsageError(
            f"seecap bench runs {path}, which is missing: the benchmark needs a "
            "source checkout installed with `pip install -e .`"
        )
    return path


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the verb's arguments (``tools/bench.py --help`` lists the finer ones)."""
    parser.add_argument("--quick", action="store_true", help="short budgets, about 15 minutes")
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("bench-out"),
        help="output folder: report.md, results.json, speed_vs_error.png",
    )
    parser.add_argument(
        "--poses",
        choices=("auto", "estimated", "truth"),
        default="auto",
        help="estimated poses (the real pipeline), the emulator's true ones, or "
        "auto: estimated unless --quick (too few views for structure from motion)",
    )


def run(args: argparse.Namespace) -> int:
    """Load ``tools/bench.py`` and run its ``main``; return its exit code."""
    path = bench_tool_path()
    sys.path.insert(0, str(path.parent))  # the tool imports its helpers from tools/benchlib
    spec = importlib.util.spec_from_file_location("seecap_bench_tool", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    argv = ["--out", str(args.out), "--poses", args.poses] + (["--quick"] if args.quick else [])
    return module.main(argv, command=shlex.join(["seecap", "bench", *argv]))
