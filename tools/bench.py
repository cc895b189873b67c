"""Benchmark: speed against error for every preset and variant, the paper's tables, capture speed.

One command regenerates every number of the report:

    python tools/bench.py [--quick] [--out bench-out] [--poses auto|estimated|truth]
                          [--presets fast ...] [--variants full ...] [--budgets 60 180 ...]
                          [--table-budget S] [--table4 | --no-table4] [--scenes | --no-scenes]
                          [--no-capture] [--fresh] [--threads N] [--ray ADDRESS] [--publish]
                          [--render-only]

1. Sessions: the ``room`` benchmark of ``make_benchmark.py``, the Table 4 sessions (input
   exposure x1/16, x1, x16 of 0.016 s at a fixed gain; DVS noise x1, x2, x4) and the other four
   ``make_benchmark.py`` scenes, recorded once under ``OUT/sessions/`` with their poses and
   reused by later runs.
2. Runs: each preset x variant, each in its own ``seecap fit`` process per budget (a ladder of
   budgets resumes one run), scored on the held-out views against the emulator's truth; on
   every scene, ``full`` beside ``oracle`` at the top budget; every row the paper's comparisons
   rank with two more seeds. The full plan is 236 minutes of training, about five hours in all
   on a 2-core machine one rung at a time (``benchlib/plan.py``). Then every row of a
   comparison that trained past that comparison's fewest steps is trained again to end there
   (``benchlib/matching.py``; at most one run per compared row, each shorter than the budget).
3. The paper's Tables 3, 9 and 4 beside our numbers, with whether each ordering holds here,
   matched on time and on steps.
4. Capture side: ``bench_decode.py``, ``bench_usb.py`` and ``bench_record.py``.

Writes ``OUT/report.md`` (a section for BENCHMARKS.md), ``OUT/results.json``,
``OUT/speed_vs_error.png`` and each scene's side-by-side views ``OUT/scenes/SESSION.png``; the
report is rewritten after every run, so an interrupted benchmark leaves a partial one
(``--render-only`` writes it again from ``OUT/results.json``). Rerunning the same command
resumes: every rung whose metrics are kept under ``OUT/runs/`` (and whose checkpoint is still
there) is read back, not trained, and the report counts them; ``--fresh`` trains every rung
again (sessions are still reused: delete ``OUT/sessions/`` to make them again). ``--publish``
(full mode) then splices the report into BENCHMARKS.md between its markers and copies the plot,
the scene images and the JSON to ``bench-results/``.
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

from benchlib.capture import CAPTURE_BENCHES, run_capture_bench
from benchlib.fits import run_ladder, run_speed_probe, rung_row
from benchlib.machine import describe_machine, exact_command, source_commit
from benchlib.plan import Ladder, make_plan, planned_rungs, planned_training_s
from benchlib.plot import speed_error_figure, write_png
from benchlib.poses_step import POSE_SOURCES, resolve_pose_source
from benchlib.publish import publish
from benchlib.readback import StaleResults, report_from_json
from benchlib.report import (
    BenchReport,
    render_markdown,
    scene_sessions,
    steps_matched_ladders,
    write_json,
)
from benchlib.results import RunRow
from benchlib.scene_images import write_scene_images
from benchlib.sessions import prepare_session

from seenerf.model.presets import PRESETS
from seenerf.model.variants import VARIANTS

TOOLS_DIR = Path(__file__).resolve().parent


def parse_arguments(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help="about 15 minutes: 20 s and 60 s budgets, 4 + 2 views, the fast "
        "preset's Table 3 variants and the oracle",
    )
    parser.add_argument("--out", type=Path, default=Path("bench-out"), help="output folder")
    parser.add_argument(
        "--poses",
        choices=("auto", *POSE_SOURCES),
        default="auto",
        help="estimated (the real pipeline), the emulator's truth, or auto: "
        "estimated unless --quick (too few views) or no estimator is installed",
    )
    parser.add_argument("--presets", nargs="+", default=list(PRESETS), choices=list(PRESETS))
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument(
        "--budgets",
        nargs="+",
        type=float,
        default=[],
        help="budget ladder in seconds (default: 20 60 quick, 60 180 600)",
    )
    parser.add_argument(
        "--table-budget",
        type=float,
        default=0.0,
        help="budget of the paper comparisons, s (default: 20 quick, 180)",
    )
    parser.add_argument(
        "--table4",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="make and fit the Table 4 sessions (default: not with --quick)",
    )
    parser.add_argument(
        "--scenes",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="make the other benchmark scenes and fit full and oracle on each "
        "(default: not with --quick)",
    )
    parser.add_argument("--no-capture", action="store_true", help="skip capture throughput")
    parser.add_argument(
        "--fresh",
        action="store_true",
        help="train every rung again instead of reading back earlier ones",
    )
    parser.add_argument(
        "--threads",
        type=int,
        default=0,
        help="torch threads of every fit (default 0: torch's own, every core; with --ray one "
        "per fit)",
    )
    parser.add_argument(
        "--ray",
        metavar="local|auto|ADDRESS",
        help="train every rung as a Ray task, the ladders side by side, one CPU each "
        "('local': Ray on this machine; the output folder must be on storage every node sees)",
    )
    parser.add_argument(
        "--render-only",
        action="store_true",
        help="measure nothing: write the report (and with --publish, BENCHMARKS.md) again from "
        "OUT/results.json, e.g. after a change to how it is written",
    )
    parser.add_argument(
        "--publish",
        action="store_true",
        help="at the end, write the report into BENCHMARKS.md and its plot and JSON into "
        "bench-results/ (full mode only)",
    )
    args = parser.parse_args(argv)
    if args.publish and args.quick:
        parser.error("--publish keeps the full report in BENCHMARKS.md; drop --quick")
    return args


def write_outputs(report: BenchReport, out: Path) -> None:
    """Rewrite ``report.md``, ``results.json`` and the plot from what is measured so far."""
    write_png(out / report.plot_name, speed_error_figure(report.rows, report.plan.sessions[0].key))
    write_scene_images(scene_sessions(report), report.plan.table_preset, out)
    (out / "report.md").write_text(render_markdown(report))
    write_json(report, out / "results.json")


def measure_capture(report: BenchReport, out: Path) -> None:
    """Run each capture-side tool in its own process; keep its figures."""
    for bench in CAPTURE_BENCHES:
        result = run_capture_bench(bench, TOOLS_DIR, out / "logs", report.plan.quick)
        report.capture.append(result)
        print(f"{bench.tool}: {result.error or result.figures}")


def prepare_sessions(report: BenchReport, out: Path) -> dict[str, Path]:
    """Record (or reuse) every session with poses; return the ready ones by key."""
    plan = report.plan
    root = out / "sessions" / f"{'quick' if plan.quick else 'full'}-{report.poses}"
    for spec in plan.sessions:
        outcome = prepare_session(spec, root, plan.views, report.poses, out / "logs")
        report.sessions.append(outcome)
        print(f"session {spec.key}: {outcome.error or 'ready'} ({outcome.folder})")
    return {s.spec.key: s.folder for s in report.sessions if not s.error}


def _not_ready(ladder) -> RunRow:
    return rung_row(ladder, 0, status="session not ready")


def run_fits(
    report: BenchReport,
    ladders: list[Ladder],
    ready: dict[str, Path],
    out: Path,
    started: float,
    args,
) -> None:
    """Every ladder in turn, the report rewritten after each; with ``--ray`` every rung a Ray
    task instead (:func:`run_fits_on_ray`)."""
    if args.ray:
        run_fits_on_ray(report, ladders, ready, out, args)
        return
    for ladder in ladders:
        if ladder.session not in ready:
            report.rows.append(_not_ready(ladder))
            continue
        report.rows += run_ladder(
            ladder, ready[ladder.session], out, fresh=args.fresh, threads=args.threads
        )
        report.wall_s = time.monotonic() - started
        write_outputs(report, out)


def run_fits_on_ray(
    report: BenchReport, ladders: list[Ladder], ready: dict[str, Path], out: Path, args
) -> None:
    """Every rung as a Ray task (ladders side by side); rows in the ladders' order."""
    from benchlib.cluster import run_ladders_on_ray

    trained = iter(
        run_ladders_on_ray(
            [(ladder, ready[ladder.session]) for ladder in ladders if ladder.session in ready],
            out,
            address=args.ray,
            fresh=args.fresh,
        )
    )
    for ladder in ladders:
        report.rows += next(trained) if ladder.session in ready else [_not_ready(ladder)]


def _exit_on_sigterm(signum: int, frame) -> None:
    raise SystemExit(128 + signum)


def render_again(out: Path, publish_it: bool) -> int:
    """Write ``out``'s report (and publish it) from its ``results.json``; 0, or 1 if stale."""
    try:
        report = report_from_json(out / "results.json")
    except (OSError, StaleResults) as error:
        print(f"bench.py: {error}", file=sys.stderr)
        return 1
    write_outputs(report, out)
    print(f"report: {out / 'report.md'} (from {out / 'results.json'})")
    if publish_it:
        folder = publish(report, out, TOOLS_DIR.parent / "BENCHMARKS.md")
        print(f"published: BENCHMARKS.md, {folder}")
    return 0


def main(argv: list[str] | None = None, command: str | None = None) -> int:
    """Run the benchmark; return 0 when every session and run succeeded, else 1."""
    args = parse_arguments(argv)
    if args.render_only:
        return render_again(args.out.resolve(), args.publish)
    signal.signal(signal.SIGTERM, _exit_on_sigterm)  # so a running child is killed with us
    started = time.monotonic()
    plan = make_plan(
        args.quick,
        tuple(args.presets),
        tuple(args.variants),
        tuple(args.budgets),
        args.table_budget,
        table4=args.table4,
        scenes=args.scenes,
    )
    out = args.out.resolve()  # children run in other folders
    out.mkdir(parents=True, exist_ok=True)
    typed = sys.argv if argv is None else ["tools/bench.py", *argv]
    report = BenchReport(
        command or exact_command(typed),
        describe_machine(),
        datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        plan,
        resolve_pose_source(args.poses, args.quick),
        source_commit(),
    )
    print(f"command: {report.command}\nmachine: {report.machine.line()}")
    print(
        f"plan: {len(plan.sessions)} sessions, {len(plan.ladders)} runs, "
        f"{planned_rungs(plan)} scored rungs, {planned_training_s(plan) / 60:.0f} min of "
        "training before start-up, renders and rungs read back"
    )
    if not args.no_capture:
        measure_capture(report, out)
    ready = prepare_sessions(report, out)
    main_session = plan.sessions[0].key
    if main_session in ready:
        report.speed = run_speed_probe(ready[main_session], out / "logs")
        print(f"preset speed: {report.speed.error or report.speed.rays_per_s}")
    run_fits(report, list(plan.ladders), ready, out, started, args)
    matched = steps_matched_ladders(report)
    if matched:
        print(f"comparisons matched on steps: {len(matched)} more runs")
        run_fits(report, matched, ready, out, started, args)
    report.wall_s = time.monotonic() - started
    write_outputs(report, out)
    print(f"report: {out / 'report.md'} ({report.wall_s / 60:.1f} min)")
    if args.publish:
        folder = publish(report, out, TOOLS_DIR.parent / "BENCHMARKS.md")
        print(f"published: BENCHMARKS.md, {folder}")
    failed = [s for s in report.sessions if s.error] + [r for r in report.rows if not r.ok]
    return 0 if not failed else 1


if __name__ == "__main__":
    sys.exit(main())
