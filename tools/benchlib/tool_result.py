"""Run one ``tools/bench_*.py`` tool's ``run(quick)`` and print its numbers as one JSON line.

    python -m benchlib.tool_result bench_usb [--quick]

The line starts with :data:`RESULT_PREFIX`; :func:`benchlib.capture.read_result` finds it in
the child's output.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys

__all__ = ["RESULT_PREFIX", "main", "result_line"]

RESULT_PREFIX = "bench result: "


def _plain(value):
    """A JSON-ready value for NumPy scalars (``json`` refuses them)."""
    if hasattr(value, "item"):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def result_line(result: dict) -> str:
    """``result`` as the one line the parent reads (NaN kept as JSON ``NaN``)."""
    return RESULT_PREFIX + json.dumps(result, default=_plain, allow_nan=True)


def main(argv: list[str] | None = None) -> int:
    """Import the tool (a module beside ``benchlib``), run it, print the line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tool", help="module name of the tool, e.g. bench_usb")
    parser.add_argument("--quick", action="store_true", help="the tool's quick mode")
    args = parser.parse_args(argv)
    result = importlib.import_module(args.tool).run(args.quick)
    print(result_line(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
