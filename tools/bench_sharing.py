"""Sharing benchmark: a fit's training speed alone and beside one busy process.

    python tools/bench_sharing.py [--out bench-out/sharing] [--steps 200] [--publish]

Records one scene (as ``seecap record --emulate`` does), measures its sensor and poses once, then
fits it three times in turn with ``seecap fit --preset fast --steps N``: alone, and beside a process
that keeps one core busy, once with the threads the fit chooses and once with one thread per core
asked for. Each row: the threads the fit used and its steps per second of training. Writes
``OUT/sharing.json`` and ``OUT/sharing.md``; ``--publish`` copies the JSON to ``bench-results/`` and
splices the report into BENCHMARKS.md between its sharing markers. About 15 minutes on 2 cores, most
of it the fit that asks for every core beside the busy one; the busy process stops once a fit has
trained (its renders are not measured).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from pathlib import Path

from benchlib.machine import scene_header
from benchlib.publish import keep_report, report_folder, report_parser
from benchlib.runner import python_command, run_measured
from benchlib.sharing import SHARING_CASES, sharing_report

from davis_io.capture import CaptureRequest, record_capture

SCENE, SEED, FRAMES = "room", 7, 16
TIMEOUT_S = 3600.0
BUSY = "while True: pass"
"""The busy process: one core kept at 100 %, as another single-threaded job would."""


def _seecap(*arguments: str) -> list[str]:
    return python_command("-m", "davis_io.cli", *arguments)


def _prepared(out: Path) -> Path:
    """The recorded session, its sensor measured and poses estimated."""
    folder = out / "sessions" / SCENE
    if (folder / "colmap" / "report.json").exists():
        return folder
    request = CaptureRequest(emulate=SCENE, seed=SEED, frames=FRAMES)
    record_capture(request, folder, overwrite=True)
    for number, argv in enumerate((["calibrate", str(folder)], ["poses", str(folder)])):
        usage = run_measured(_seecap(*argv), out / "logs" / f"prepare-{number}.log")
        if usage.returncode != 0:
            raise SystemExit(f"seecap {argv[0]} failed: see {out / 'logs'}")
    return folder


def _threads_used(log_text: str) -> str:
    """The thread count a fit's log states (``threads: 1 of 2 cores ...``)."""
    for line in log_text.splitlines():
        if "threads: " in line:
            return line.split("threads: ", 1)[1].split(" ", 1)[0]
    return "?"


@contextmanager
def _busy_while_training(run: Path) -> Iterator[None]:
    """Keep one core busy until the fit in ``run`` says it has trained (its renders run alone).

    Beside a busy core, a fit that asked for every core renders its views many times slower
    too; they are not what is measured.
    """
    (run / "log.txt").unlink(missing_ok=True)  # an earlier run's, which says it has trained
    done = threading.Event()

    def busy() -> None:
        process = subprocess.Popen([sys.executable, "-c", BUSY])
        try:
            while not done.is_set() and not _trained(run / "log.txt"):
                time.sleep(0.5)
        finally:
            process.kill()
            process.wait()

    thread = threading.Thread(target=busy, daemon=True)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()


def _trained(log: Path) -> bool:
    try:
        return "  trained " in log.read_text()
    except FileNotFoundError:
        return False


def _fit(name: str, session: Path, steps: int, out: Path) -> dict:
    run = session / "fit" / name
    argv = ["fit", str(session), "--preset", "fast", "--steps", str(steps), "--run", name]
    argv += ["--fresh"]
    if name == "busy-all":
        argv += ["--threads", str(len(os.sched_getaffinity(0)))]
    beside = _busy_while_training(run) if name.startswith("busy") else nullcontext()
    with beside:
        usage = run_measured(_seecap(*argv), out / "logs" / f"fit-{name}.log", timeout_s=TIMEOUT_S)
    if usage.returncode != 0:
        return {"error": f"seecap fit exited {usage.returncode}; see logs/fit-{name}.log"}
    training = json.loads((run / "metrics.json").read_text())["training"]
    return {
        "threads": _threads_used((run / "log.txt").read_text()),
        "steps": training["steps"],
        "training_s": training["elapsed_s"],
        "steps_per_s": training["steps"] / training["elapsed_s"],
        "wall_s": usage.wall_s,
    }


def main(argv: list[str] | None = None) -> int:
    parser = report_parser(__doc__.splitlines()[0], "bench-out/sharing")
    parser.add_argument("--steps", type=int, default=200, help="training steps of each fit")
    args = parser.parse_args(argv)
    out = report_folder(args.out)
    fit = f"seecap fit SESSION --preset fast --steps {args.steps} [--threads CORES]"
    document = {**scene_header(SCENE, SEED, FRAMES, fit), "busy": f"python -c '{BUSY}'"}
    session = _prepared(out)
    document["cases"] = {name: _fit(name, session, args.steps, out) for name in SHARING_CASES}
    keep_report(out, "sharing", document, sharing_report(document), args.publish)
    return 1 if any("error" in case for case in document["cases"].values()) else 0


if __name__ == "__main__":
    sys.exit(main())
