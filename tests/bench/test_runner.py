import sys

from benchlib.machine import cpu_model
from benchlib.runner import run_measured


def test_each_child_reports_its_own_peak_memory(tmp_path):
    big = run_measured(
        [sys.executable, "-c", "b = bytearray(300_000_000); print('done')"], tmp_path / "big.log"
    )
    small = run_measured([sys.executable, "-c", "print('small')"], tmp_path / "small.log")
    assert big.returncode == 0 and (tmp_path / "big.log").read_text() == "done\n"
    assert big.peak_rss_mb > 300  # the 300 MB buffer plus the interpreter
    # Neither the earlier child's maximum nor this test process's (which holds torch and more).
    assert small.peak_rss_mb < 60
    assert big.cpu_s >= 0 and big.wall_s > 0


def test_exit_code_and_time_limit(tmp_path):
    failed = run_measured([sys.executable, "-c", "raise SystemExit(3)"], tmp_path / "f.log")
    assert failed.returncode == 3 and not failed.timed_out
    slow = run_measured(
        [sys.executable, "-c", "import time; time.sleep(30)"], tmp_path / "s.log", timeout_s=0.5
    )
    assert slow.timed_out and slow.returncode == -9 and slow.wall_s < 10
    assert slow.peak_rss_mb != slow.peak_rss_mb  # NaN: killed before anything was measured


def test_cpu_model():
    text = "processor\t: 0\nvendor_id\t: GenuineIntel\nmodel name\t: Intel(R) Xeon(R) Processor\n"
    assert cpu_model(text) == "Intel(R) Xeon(R) Processor"
    assert cpu_model("") == "unknown CPU"


def test_a_published_command_names_no_folder_of_the_machine(tmp_path, monkeypatch):
    from benchlib.machine import exact_command

    monkeypatch.chdir(tmp_path)
    typed = ["tools/bench_blind.py", "--out", str(tmp_path / "out" / "blind"), "--jobs", "2"]
    assert exact_command(typed).endswith(" tools/bench_blind.py --out out/blind --jobs 2")
    outside = exact_command(["tools/bench.py", "--out", str(tmp_path.parent / "elsewhere")])
    assert outside.endswith(" --out ../elsewhere") and str(tmp_path) not in outside
