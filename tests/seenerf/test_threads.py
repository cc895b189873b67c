"""`--threads N` bounds every CPU pool of the process, not torch's alone; 0 takes the free cores."""

import json
import subprocess
import sys

PROBE = """
import json, sys
import cv2, torch
from threadpoolctl import threadpool_info
from seenerf.train.threads import limit_threads
if sys.argv[1] != "untouched":
    limit_threads(int(sys.argv[1]))
print(json.dumps({
    "torch": torch.get_num_threads(),
    "blas": [pool["num_threads"] for pool in threadpool_info()],
    "opencv": cv2.getNumThreads(),
}))
"""


def _pools(count: int | str) -> dict:
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(count)], capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout)


def test_one_thread_means_one_in_torch_blas_and_opencv():
    pools = _pools(1)
    assert pools["torch"] == 1 and pools["opencv"] == 1
    assert pools["blas"] and set(pools["blas"]) == {1}  # numpy's OpenBLAS is among them


def test_zero_leaves_the_defaults():
    assert _pools(0) == _pools("untouched")


def test_a_fit_takes_the_cores_other_work_leaves_free():
    from seenerf.train.threads import threads_for

    assert threads_for(2, 0.1) == 2  # an idle machine: every core
    assert threads_for(2, 0.9) == 1  # one busy process: the other core
    assert threads_for(2, 2.0) == 1 and threads_for(8, 7.6) == 1  # at least one
    assert threads_for(8, 2.4) == 6 and threads_for(8, 2.5) == 5  # half a core busy counts


def test_how_busy_the_cores_are_is_read_from_proc_stat(tmp_path, monkeypatch):
    import seenerf.train.threads as threads

    stat = tmp_path / "stat"
    # user nice system idle iowait irq softirq steal: 30 of 100 jiffies busy, then 110 of 300.
    texts = iter(["cpu 20 0 10 60 10 0 0 0 0 0\ncpu0 1\n", "cpu 70 0 40 170 20 0 0 0 0 0\n"])
    monkeypatch.setattr(threads.time, "sleep", lambda s: stat.write_text(next(texts)))
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 2)
    stat.write_text(next(texts))
    # Between the reads: 80 busy (50 user + 30 system) of 200 jiffies on 2 cores = 0.8 cores.
    assert threads.busy_cores(0.0, stat) == 0.8
    assert threads.busy_cores(0.0, tmp_path / "missing") is None


def test_asked_threads_are_taken_as_given():
    from seenerf.train.threads import choose_threads

    count, why = choose_threads(3)
    assert count == 3 and why.startswith("threads: 3 (as asked)")
