"""The ``seecap`` console entry point: a table of verbs, each a module with two functions.

A verb module defines ``HELP`` (one line), ``add_arguments(parser)`` and ``run(args) -> int``.
Modules are imported only when their verb runs, so ``seecap inspect`` never loads torch.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from davis_io import SeecapError, __version__

__all__ = ["VERBS", "main"]

VERBS: dict[str, str] = {
    # verb: module that implements it
    "inspect": "davis_io.cli.inspect_verb",
    "record": "davis_io.cli.record_verb",
    "bins": "davis_io.cli.bins_verb",
    "calibrate": "davis_io.cli.calibrate_verb",
    "poses": "davis_io.cli.poses_verb",
    "export": "davis_io.cli.export_verb",
    "devices": "davis_io.cli.devices_verb",
    "doctor": "davis_io.cli.doctor_verb",
    "udev": "davis_io.cli.udev_verb",
    "fit": "seenerf.cli.fit_verb",
    "render": "seenerf.cli.render_verb",
    "eval": "seenerf.cli.eval_verb",
}
"""Every verb of ``seecap``, in the order ``--help`` lists them."""

EXIT_OK = 0
EXIT_ERROR = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


def _build_parser() -> tuple[argparse.ArgumentParser, dict[str, object]]:
    parser = argparse.ArgumentParser(
        prog="seecap",
        description="DAVIS event camera to sharp HDR 3-D scenes: record, inspect, poses, fit.",
    )
    parser.add_argument("--version", action="version", version=f"seecap {__version__}")
    verbs = parser.add_subparsers(dest="verb", metavar="VERB")
    modules = {}
    for name, module_name in VERBS.items():
        module = importlib.import_module(module_name)
        sub = verbs.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(sub)
        modules[name] = module
    return parser, modules


def main(argv: list[str] | None = None) -> int:
    """Run ``seecap``; return the process exit code (0 ok, 1 error, 2 usage, 130 Ctrl-C)."""
    parser, modules = _build_parser()
    args = parser.parse_args(argv)
    if args.verb is None:
        parser.print_help()
        return EXIT_USAGE
    try:
        return int(modules[args.verb].run(args) or EXIT_OK)
    except KeyboardInterrupt:
        print("seecap: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except SeecapError as error:
        print(f"seecap {args.verb}: {error}", file=sys.stderr)
        return EXIT_ERROR


if __name__ == "__main__":
    sys.exit(main())
