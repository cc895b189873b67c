"""Fits as Ray tasks on a local instance: at once, equal to the sequential fit, retried, apart."""

import json
import os
import re
import signal
import threading
import time
from datetime import datetime

import torch

from seenerf.cli.cluster import fit_on_ray
from seenerf.cli.sessions import fit_kept_apart
from seenerf.model.config import FitConfig

FIT = FitConfig.of(
    steps=120, batch_pixels=64, warm_steps=2, threads=1, register_test_views=False, seed=3
)
RUN = "fast-full"


def _training_span(log_text: str) -> tuple[datetime, datetime]:
    """When a run's log says its training started and ended."""
    stamps = {}
    for line in log_text.splitlines():
        for key, marker in (("start", "  training "), ("end", "  trained ")):
            if marker in line:
                stamps[key] = datetime.strptime(line[:19], "%Y-%m-%d %H:%M:%S")
    return stamps["start"], stamps["end"]


def _scores(metrics: dict) -> tuple:
    return (
        metrics["hdr"]["psnr"],
        metrics["novel_exposure"]["psnr"],
        metrics["training"]["steps"],
        [record["val_psnr"] for record in metrics["training"]["history"]],
    )


def test_two_fits_at_once_equal_the_sequential_fit_and_a_bad_session_is_kept_apart(
    local_ray, copies, tmp_path
):
    first, second, alone = copies("first", "second", "alone")
    unreadable = tmp_path / "unreadable"
    unreadable.mkdir()
    fits = fit_on_ray([first, second, unreadable], FIT, address="local")
    threads = torch.get_num_threads()
    try:
        reference = fit_kept_apart(alone, FIT)
    finally:
        torch.set_num_threads(threads)
    assert reference.error == ""
    assert [fit.session for fit in fits] == [first, second, unreadable]
    assert [fit.error == "" for fit in fits] == [True, True, False]
    assert str(unreadable / "session.json") in fits[2].error
    for fit in fits[:2]:
        assert fit.run_dir == fit.session / "fit" / RUN
        assert _scores(fit.metrics) == _scores(reference.metrics)
        assert json.loads((fit.run_dir / "metrics.json").read_text())["training"]["steps"] == 120
    # at once: each run's training started before the other's ended
    (start_a, end_a), (start_b, end_b) = (
        _training_span((fit.run_dir / "log.txt").read_text()) for fit in fits[:2]
    )
    assert start_a < end_b and start_b < end_a


def _kill_the_fit_at_its_first_checkpoint(run_dir, killed: list, timeout_s: float = 300.0):
    """SIGKILL the process holding the run's lock once its first checkpoint is on disk."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if (run_dir / "checkpoint.pt").exists():
            pid = json.loads((run_dir / ".writer.lock").read_text())["pid"]
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)
            return
        time.sleep(0.05)


def test_a_fit_whose_worker_dies_is_retried_and_resumes_from_its_checkpoint(local_ray, copies):
    (session,) = copies("killed")
    run_dir = session / "fit" / RUN
    killed = []
    killer = threading.Thread(target=_kill_the_fit_at_its_first_checkpoint, args=(run_dir, killed))
    killer.start()
    (fit,) = fit_on_ray([session], FIT.replaced(steps=300), address="local")
    killer.join()
    assert killed and killed[0] != os.getpid()
    assert fit.error == ""
    resumed = re.findall(r"resuming at step (\d+)", (run_dir / "log.txt").read_text())
    assert len(resumed) == 1 and 0 < int(resumed[0]) < 300
    assert fit.metrics["training"]["steps"] == 300
