"""Where a run's software came from: seecap's version and commit, torch's, the device used."""

from __future__ import annotations

import platform
import subprocess
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np
import torch

__all__ = ["software", "source_commit"]


def source_commit() -> str:
    """The checkout's commit, ``+changes`` when its tracked files differ ("unknown" outside one)."""
    root = Path(__file__).resolve().parents[1]
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=root, capture_output=True, text=True, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=root,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return commit + ("+changes" if dirty else "")


def software(device: str) -> dict:
    """The versions a run was made with and the device it trained on (saved in config.json)."""
    try:
        seecap = version("seecap")
    except PackageNotFoundError:
        seecap = "unknown"
    return {
        "seecap": seecap,
        "commit": source_commit(),
        "python": platform.python_version(),
        "torch": torch.__version__,
        "numpy": np.__version__,
        "device": device,
        "threads": torch.get_num_threads() if device == "cpu" else 0,
    }
