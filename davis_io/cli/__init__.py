"""The ``seecap`` console entry point: a table of verbs, each a module with two functions.

A verb module defines ``HELP`` (one line), ``add_arguments(parser)`` and ``run(args) -> int``.
Modules are imported only when their verb runs, so ``seecap inspect`` never loads torch.
"""

from __future__ import annotations

import argparse
import importlib
import os
import signal
import sys
import threading
import warnings
from pathlib import Path
from typing import NoReturn

from davis_io import SeecapError, __version__
from davis_io.errors import UsageError, describe_error

__all__ = ["VERBS", "console", "end_process", "main"]

# Set before any verb imports numpy (nothing above does). numpy asks the kernel for huge pages
# for every large array, and where transparent huge pages are defragmented on request (Debian's
# default), a process that has churned gigabytes then waits on memory compaction at each new
# array: the calibration of 24 M events took 27.4 s with the advice and 19.9 s without, with the
# same values (its pixel blocks' sort 2.4 s against 0.3 s). A user's own setting stands.
os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")

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
    "report": "seenerf.cli.report_verb",
}
"""Every verb of ``seecap``, in the order ``--help`` lists them."""

EXIT_OK = 0
EXIT_ERROR = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 128 + signal.SIGTERM


class _Terminated(BaseException):
    """SIGTERM arrived (``kill``, a scheduler's stop): unwound like Ctrl-C, closing every file."""


def _raise_terminated(signum: int, frame) -> None:
    raise _Terminated


def _build_parser() -> tuple[argparse.ArgumentParser, dict[str, object]]:
    parser = argparse.ArgumentParser(
        prog="seecap",
        description="DAVIS event camera to sharp HDR 3-D scenes: record, inspect, poses, fit.",
    )
    parser.add_argument("--version", action="version", version=f"seecap {__version__}")
    parser.add_argument(
        "--debug", action="store_true", help="show the traceback of a failure instead of a line"
    )
    verbs = parser.add_subparsers(dest="verb", metavar="VERB")
    modules = {}
    for name, module_name in VERBS.items():
        module = importlib.import_module(module_name)
        sub = verbs.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(sub)
        modules[name] = module
    return parser, modules


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"seecap: warning: {message}", file=sys.stderr)


def _failure(error: BaseException, verb: str, debug: bool) -> int:
    """One line for a failure, its exit code (2 for a usage error, 1 for any other)."""
    if debug:
        raise error
    print(f"seecap: error: {verb}: {describe_error(error)}", file=sys.stderr)
    if isinstance(error, SeecapError) and error.exit_status is not None:
        return error.exit_status
    return EXIT_USAGE if isinstance(error, UsageError) else EXIT_ERROR


def _check_paths(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """A usage error for a path no file system can hold (a NUL byte), before any verb runs."""
    for name, value in vars(args).items():
        for path in value if isinstance(value, list) else [value]:
            if isinstance(path, Path) and "\x00" in str(path):
                parser.error(f"argument {name}: {str(path)!r} holds a NUL byte, which no path may")


def main(argv: list[str] | None = None) -> int:
    """Run ``seecap``; return the exit code (0 ok, 1 failure, 2 usage, 130 Ctrl-C, 143 SIGTERM).

    SIGTERM unwinds like Ctrl-C (``record`` and ``fit`` handle both themselves, to close the
    session or save a checkpoint). Every failure is one line ``seecap: error: VERB: what, where
    and what to do`` and warnings are ``seecap: warning: ...`` lines; ``--debug`` shows
    tracebacks instead.
    """
    parser, modules = _build_parser()
    args = parser.parse_args(argv)
    if args.verb is None:
        parser.print_help()
        return EXIT_USAGE
    _check_paths(parser, args)
    shown = warnings.showwarning
    if not args.debug:
        warnings.showwarning = _show_warning
    in_main = threading.current_thread() is threading.main_thread()
    terminate = signal.signal(signal.SIGTERM, _raise_terminated) if in_main else None
    try:
        status = int(modules[args.verb].run(args) or EXIT_OK)
        sys.stdout.flush()  # a reader that has gone shows here, not at the interpreter's exit
        return status
    except KeyboardInterrupt:
        print("seecap: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except _Terminated:
        print(f"seecap: {args.verb}: terminated (SIGTERM)", file=sys.stderr)
        return EXIT_TERMINATED
    except BrokenPipeError:  # the reader (``| head``) has gone: stop quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except Exception as error:  # noqa: BLE001 - the one place every failure becomes a line
        return _failure(error, args.verb, args.debug)
    finally:
        warnings.showwarning = shown
        if terminate is not None:
            signal.signal(signal.SIGTERM, terminate)


def end_process(status: int) -> NoReturn:
    """Exit with ``status``; past HDF5's clean-up when it holds a file it could not close.

    A file HDF5 failed to close (a full disk) crashes the library's exit handlers; the process
    then ends at once, its output flushed, its recorded data readable after a repair.
    """
    from davis_io.session.writer import abandoned_files

    if abandoned_files():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    sys.exit(status)


def console() -> NoReturn:
    """The ``seecap`` console script: :func:`main`, then :func:`end_process`."""
    end_process(main())


if __name__ == "__main__":
    console()
