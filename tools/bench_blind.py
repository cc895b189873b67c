"""Blind benchmark: sessions with randomly drawn sensors, each fitted from its recording.

    python tools/bench_blind.py [--out bench-out/blind] [--budget 600] [--sessions room-s10 ...]
                                [--fresh] [--jobs 2] [--ray ADDRESS] [--publish]
                                [--render-only] [--merge FOLDER [FOLDER ...]]

For every session of :data:`benchlib.blind.BLIND_SESSIONS`: record it with a random sensor, fit
``full`` end to end (calibration and poses included) with the budget, then ``white-box`` (the
sensor's true values) and ``oracle`` for as long as ``full`` trained; score all three by the
fit's own protocol. Kept sessions and runs are read back (``--fresh`` redoes them). Writes
``OUT/blind.json`` and ``OUT/blind.md`` after every session; about 35 minutes per session on
2 cores. ``--publish`` then copies ``blind.json`` to ``bench-results/`` and splices the report
into BENCHMARKS.md between its blind-benchmark markers; ``--render-only`` prints (and with
``--publish`` publishes) ``OUT/blind.json`` as the run left it, fitting nothing. The commit,
command and machine stated are those at the run's start. ``--merge`` reports the runs left in
several folders as one, each session from the last folder that has it, every run's commit and
command stated beside its sessions; a folder may hold a merge itself (``--merge bench-results
../part`` puts a part run again into what is published).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from benchlib.blind import (
    BLIND_SESSIONS,
    blind_report,
    merged_runs,
    rows_to_json,
    run_blind_session,
)
from benchlib.machine import run_header
from benchlib.publish import BLIND_BEGIN, BLIND_END, publish_section, report_parser

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str] | None = None) -> int:
    parser = report_parser(__doc__.splitlines()[0], "bench-out/blind")
    parser.add_argument("--budget", type=float, default=600.0, help="full's budget, seconds")
    parser.add_argument(
        "--sessions", nargs="+", default=[s.key for s in BLIND_SESSIONS], help="session keys"
    )
    parser.add_argument("--fresh", action="store_true", help="record and fit everything again")
    parser.add_argument(
        "--render-only",
        action="store_true",
        help="report OUT/blind.json as the last run left it, fitting nothing",
    )
    parser.add_argument(
        "--merge",
        nargs="+",
        type=Path,
        metavar="FOLDER",
        help="report the runs these folders' blind.json hold as one, fitting nothing",
    )
    parser.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="sessions run side by side, the cores shared out among them (each fit gets fewer "
        "threads, so fewer steps in its budget: scores can only be lower than alone)",
    )
    parser.add_argument(
        "--ray",
        metavar="local|auto|ADDRESS",
        help="each session as a Ray task of (cores / --jobs) CPUs ('local': Ray on this "
        "machine; the output folder must be on storage every node sees)",
    )
    args = parser.parse_args(argv)
    args.out = args.out.resolve()  # Ray's workers run in other folders
    if args.merge:
        document = merged_runs([json.loads((f / "blind.json").read_text()) for f in args.merge])
    elif args.render_only:
        document = json.loads((args.out / "blind.json").read_text())
    else:
        document = _run_sessions(args)
    print(blind_report(document))
    if args.publish:
        publish_section(
            ROOT, "blind.json", document, blind_report(document), BLIND_BEGIN, BLIND_END
        )
    return 0


def _run_sessions(args: argparse.Namespace) -> dict:
    """Record, fit and score the chosen sessions; ``OUT/blind.json`` after each one."""
    chosen = [s for s in BLIND_SESSIONS if s.key in args.sessions]
    threads = max(1, (os.cpu_count() or 1) // args.jobs)
    if args.jobs > 1:
        os.environ["OMP_NUM_THREADS"] = str(threads)  # the children's torch threads
    start, done = time.time(), {}
    header = {  # as at the start: edits made while it runs are not what it measured
        **run_header(),
        "budget_s": args.budget,
        "jobs": args.jobs,
        "threads_per_fit": threads,
    }

    def run(spec):
        return spec.key, run_blind_session(spec, args.out, args.budget, fresh=args.fresh)

    with contextlib.ExitStack() as stack:
        if args.ray:
            from benchlib.cluster import map_on_ray

            finished = map_on_ray(run, chosen, address=args.ray, cpus=threads)
        else:
            finished = stack.enter_context(ThreadPoolExecutor(args.jobs)).map(run, chosen)
        for key, row in finished:
            done[key] = row
            document = {
                **header,
                "wall_s": time.time() - start,
                "rows": rows_to_json([done[s.key] for s in chosen if s.key in done]),
            }
            (args.out / "blind.json").write_text(json.dumps(document, indent=1, default=str))
            (args.out / "blind.md").write_text(blind_report(document) + "\n")
    return document


if __name__ == "__main__":
    sys.exit(main())
