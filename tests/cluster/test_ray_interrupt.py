"""Ctrl-C on ``seecap fit --ray local``: every task cancelled, every checkpoint saved and readable.

A module of its own: its command starts its own Ray instance, not beside another test's.
"""

import os
import signal
import subprocess
import sys
import time

import pytest
import torch

RUN = "fast-full"


def _training_started(run_dir) -> bool:
    log = run_dir / "log.txt"
    return log.exists() and "  training " in log.read_text()


def test_ctrl_c_cancels_every_fit_and_each_saves_its_checkpoint(copies):
    sessions = copies("one", "two")
    runs = [session / "fit" / RUN for session in sessions]
    command = [sys.executable, "-m", "davis_io.cli", "fit", *map(str, sessions), "--ray", "local"]
    options = ["--steps", "100000", "--batch-pixels", "64", "--warm-steps", "2", "--quiet"]
    fit = subprocess.Popen(
        [*command, *options],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its Ray processes go with it if it must be killed
        # A command started in the background of a script inherits SIGINT ignored, and Python
        # then never raises KeyboardInterrupt: give the fit the disposition a terminal gives.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        deadline = time.monotonic() + 300
        while not all(map(_training_started, runs)) and time.monotonic() < deadline:
            time.sleep(0.2)
        time.sleep(1.0)
        fit.send_signal(signal.SIGINT)
        out, err = fit.communicate(timeout=180)
    except subprocess.TimeoutExpired:
        os.killpg(fit.pid, signal.SIGKILL)
        pytest.fail(f"still running 180 s after Ctrl-C; it printed:\n{fit.communicate()[1]}")
    finally:
        if fit.poll() is None:
            os.killpg(fit.pid, signal.SIGKILL)
    assert fit.returncode == 130, err
    assert err.strip().splitlines()[-1] == "seecap: interrupted"
    for run in runs:
        state = torch.load(run / "checkpoint.pt", map_location="cpu", weights_only=True)
        assert 0 < state["steps"] < 100000
