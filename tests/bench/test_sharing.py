"""The sharing benchmark's report: each fit's speed and its share of the speed alone."""

import bench_sharing  # tools/, on the path by conftest
from benchlib.sharing import sharing_report


def _document(busy_auto_s: float) -> dict:
    def case(threads: str, seconds: float) -> dict:
        return {
            "threads": threads,
            "steps": 300,
            "training_s": seconds,
            "steps_per_s": 300 / seconds,
        }

    return {
        "commit": "abc",
        "machine": "a machine",
        "command": "python tools/bench_sharing.py",
        "scene": "room",
        "seed": 7,
        "frames": 16,
        "fit": "seecap fit SESSION --preset fast --steps 300 [--threads CORES]",
        "busy": "python -c 'while True: pass'",
        "cases": {
            "alone": case("2", 30.0),  # 10 steps/s
            "busy-auto": case("1", busy_auto_s),
            "busy-all": case("2", 300.0),  # 1 step/s
        },
    }


def test_each_fit_shows_its_speed_and_its_share_of_the_speed_alone():
    report = sharing_report(_document(45.0))  # 6.67 steps/s
    assert "| alone | 2 | 300 in 30.0 s | 10.00 | 1.00 |" in report
    assert "| busy-auto | 1 | 300 in 45.0 s | 6.67 | 0.67 |" in report
    assert "| busy-all | 2 | 300 in 300.0 s | 1.00 | 0.10 |" in report
    assert "with the threads the fit chooses: 0.67 (met)." in report


def test_a_fit_beside_the_busy_process_under_half_its_speed_misses():
    assert "chooses: 0.40 (missed)." in sharing_report(_document(75.0))  # 4 steps/s


def test_a_failed_fit_is_a_row_that_says_so_and_leaves_the_verdict_unmeasured():
    document = _document(45.0)
    document["cases"]["busy-auto"] = {"error": "seecap fit exited 1; see logs/fit-busy-auto.log"}
    report = sharing_report(document)
    assert "| busy-auto | failed: seecap fit exited 1" in report
    assert "chooses: not measured." in report


def test_the_threads_a_fit_used_are_read_from_its_log():
    chosen = "2026-11-29 01:00:00  threads: 1 of 2 cores (1.0 cores busy with other work)\n"
    asked = "2026-11-29 01:00:00  threads: 2 (as asked) on 2 cores\nthreads: 1 from now on\n"
    assert bench_sharing._threads_used(chosen + "training fast full\n") == "1"
    assert bench_sharing._threads_used(asked) == "2"
    assert bench_sharing._threads_used("no such line\n") == "?"
