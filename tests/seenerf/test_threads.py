"""`--threads N` bounds every CPU pool of the process, not torch's alone; none given takes the free
cores."""

import json
import subprocess
import sys

import pytest
import torch

PROBE = """
import json, sys
import cv2, torch
from threadpoolctl import threadpool_info
from seenerf.train.threads import limit_threads
if sys.argv[1] != "untouched":
    limit_threads(None if sys.argv[1] == "None" else int(sys.argv[1]))
print(json.dumps({
    "torch": torch.get_num_threads(),
    "blas": [pool["num_threads"] for pool in threadpool_info()],
    "opencv": cv2.getNumThreads(),
}))
"""


def _pools(count: int | str | None) -> dict:
    done = subprocess.run(
        [sys.executable, "-c", PROBE, str(count)], capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout)


def test_one_thread_means_one_in_torch_blas_and_opencv():
    pools = _pools(1)
    assert pools["torch"] == 1 and pools["opencv"] == 1
    assert pools["blas"] and set(pools["blas"]) == {1}  # numpy's OpenBLAS is among them


def test_no_count_leaves_the_defaults():
    assert _pools(None) == _pools("untouched")


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
    monkeypatch.setattr(threads.time, "process_time", lambda: 7.0)  # this process: idle
    stat.write_text(next(texts))
    # Between the reads: 80 busy (50 user + 30 system) of 200 jiffies on 2 cores = 0.8 cores.
    assert threads.busy_cores(0.0, stat) == pytest.approx(0.8)
    assert threads.busy_cores(0.0, tmp_path / "missing") is None


def test_a_fit_leaves_its_own_work_out_of_what_others_do(tmp_path, monkeypatch):
    import seenerf.train.threads as threads

    stat = tmp_path / "stat"
    stat.write_text("cpu 0 0 0 100 0 0 0 0\n")
    clock = iter([10.0, 10.5])  # this process: half a core over the second between the looks
    monkeypatch.setattr(threads.time, "process_time", lambda: next(clock))
    monkeypatch.setattr(threads.os, "cpu_count", lambda: 2)
    monkeypatch.setattr(threads.os, "sysconf", lambda name: 100)  # jiffies per second
    watch = threads.CoreWatch(stat)
    stat.write_text("cpu 130 0 30 140 0 0 0 0\n")  # 160 of 200 jiffies busy: 1.6 cores
    assert watch.others() == pytest.approx(1.1)  # 1.6 - 0.5 of its own


def test_a_fit_with_automatic_threads_gives_a_core_up_when_other_work_starts(
    tiny_scene, monkeypatch
):
    import seenerf.train.threads as threads
    import seenerf.train.trainer as trainer_module
    from seenerf.model.config import FitConfig
    from seenerf.train.methods import make_method
    from seenerf.train.threads import CoreWatch
    from seenerf.train.trainer import Trainer

    monkeypatch.setattr(trainer_module, "THREADS_CHECK_S", 0.0)
    monkeypatch.setattr(CoreWatch, "others", lambda self: 1.0)
    monkeypatch.setattr(threads.os, "sched_getaffinity", lambda pid: {0, 1})
    before = torch.get_num_threads()
    lines = []
    try:
        torch.set_num_threads(2)  # whatever an earlier test left
        config = FitConfig.of(steps=3, batch_pixels=8, warm_steps=2, validation_share=0.1)
        Trainer(make_method(tiny_scene, config), log=lines.append).train()
        assert torch.get_num_threads() == 1
    finally:
        torch.set_num_threads(before)
    assert "threads: 1 from now on (1.0 cores busy with other work)" in lines
    asked, lines = FitConfig.of(steps=3, batch_pixels=8, warm_steps=2, threads=2), []
    try:
        torch.set_num_threads(2)  # as the fit sets a count asked for
        Trainer(make_method(tiny_scene, asked), log=lines.append).train()
        assert torch.get_num_threads() == 2  # and the trainer keeps it
    finally:
        torch.set_num_threads(before)
    assert not [line for line in lines if "from now on" in line]


def test_asked_threads_are_taken_as_given():
    from seenerf.train.threads import choose_threads

    count, why = choose_threads(3)
    assert count == 3 and why.startswith("threads: 3 (as asked)")
