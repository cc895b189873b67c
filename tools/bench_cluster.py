"""Cluster benchmark: the quick plan run locally, then as Ray tasks on a local instance.

    python tools/bench_cluster.py [--out bench-out/cluster] [--publish]

Runs ``tools/bench.py --quick --no-capture --fresh`` twice in child processes, each fit on one
core: first one rung after another (``--threads 1``), then with ``--ray local`` (every rung a
Ray task of one CPU, the ladders side by side), and puts wall times and every rung's scores side
by side. Writes ``OUT/cluster.json`` and ``OUT/cluster.md``; ``--publish``
copies the JSON to ``bench-results/`` and splices the report into BENCHMARKS.md between its
cluster markers. About 15 minutes on 2 cores.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

from benchlib.cluster import FIT_THREADS
from benchlib.machine import exact_command, run_header
from benchlib.publish import keep_report, report_folder, report_parser
from benchlib.side_by_side import ROW_FIELDS, side_by_side_report

ROOT = Path(__file__).resolve().parents[1]
WAYS = {"local": ["--threads", str(FIT_THREADS)], "ray": ["--ray", "local"]}
"""Both give each fit one core, so that their scores compare: one fit at a time, or side by side."""


def _run(way: str, out: Path) -> dict:
    """The quick plan one way, in a child process; its wall time and every rung's scores."""
    arguments = ["tools/bench.py", "--quick", "--no-capture", "--fresh", "--out", str(out / way)]
    command = [*arguments, *WAYS[way]]
    start = time.monotonic()
    with open(out / f"{way}.log", "wb") as log:
        done = subprocess.run([sys.executable, "-u", *command], cwd=ROOT, stdout=log, stderr=log)
    wall_s = time.monotonic() - start
    results = json.loads((out / way / "results.json").read_text())
    rows = [
        {
            **{key: row[key] for key in ROW_FIELDS},
            "hdr_psnr": row["hdr_psnr"],
            "novel_psnr": row["novel_psnr"],
        }
        for row in results["rows"]
    ]
    return {
        "command": exact_command(command),
        "returncode": done.returncode,
        "wall_s": wall_s,
        "rows": rows,
    }


def main(argv: list[str] | None = None) -> int:
    parser = report_parser(__doc__.splitlines()[0], "bench-out/cluster")
    args = parser.parse_args(argv)
    out = report_folder(args.out)
    document = {
        **run_header(),
        "ray_cpus_per_fit": FIT_THREADS,
        "runs": {},
    }
    for way in WAYS:
        document["runs"][way] = _run(way, out)
        print(f"{way}: {document['runs'][way]['wall_s'] / 60:.1f} min")
    report = side_by_side_report(document)
    keep_report(out, "cluster", document, report, args.publish)
    failed = [way for way, run in document["runs"].items() if run["returncode"] != 0]
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
