import argparse
from pathlib import Path

from davis_io.cli import VERBS
from seenerf.cli import bench_verb


def test_bench_verb_finds_the_tool_of_this_checkout():
    assert VERBS["bench"] == "seenerf.cli.bench_verb"
    repository = Path(__file__).resolve().parents[2]
    assert bench_verb.bench_tool_path() == repository / "tools" / "bench.py"


def test_bench_verb_arguments():
    parser = argparse.ArgumentParser()
    bench_verb.add_arguments(parser)
    args = parser.parse_args(["--quick", "--out", "somewhere"])
    assert (args.quick, args.out, args.poses) == (True, Path("somewhere"), "auto")
