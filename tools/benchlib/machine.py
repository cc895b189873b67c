"""The machine a benchmark ran on, and the exact command that ran it."""

from __future__ import annotations

import os
import platform
import shlex
import sys
from dataclasses import dataclass
from pathlib import Path

from seenerf.provenance import source_commit

__all__ = [
    "Machine",
    "cpu_model",
    "describe_machine",
    "exact_command",
    "measured_line",
    "run_header",
    "scene_header",
    "source_commit",
]


@dataclass(frozen=True)
class Machine:
    """CPU, cores, software versions and the training device."""

    cpu: str
    cores: int
    system: str
    python: str
    numpy: str
    torch: str
    device: str
    threads: int
    load_average: tuple[float, float, float]

    def line(self) -> str:
        """One line for the report."""
        load = ", ".join(f"{value:.2f}" for value in self.load_average)
        return (
            f"{self.cpu}, {self.cores} cores; {self.system}; Python {self.python}, numpy "
            f"{self.numpy}, torch {self.torch} ({self.threads} threads), device {self.device}; "
            f"load average at start {load}"
        )


def cpu_model(cpuinfo_text: str) -> str:
    """The first ``model name`` of a ``/proc/cpuinfo`` text ("unknown CPU" when absent)."""
    for line in cpuinfo_text.splitlines():
        key, _, value = line.partition(":")
        if key.strip() == "model name" and value.strip():
            return value.strip()
    return "unknown CPU"


def describe_machine() -> Machine:
    """Read the machine's facts (imports torch, so call it once)."""
    import numpy
    import torch

    cpuinfo = Path("/proc/cpuinfo")
    text = cpuinfo.read_text() if cpuinfo.exists() else ""
    device = "cuda" if torch.cuda.is_available() else "cpu"
    if device == "cuda":
        device = f"cuda ({torch.cuda.get_device_name(0)})"
    return Machine(
        cpu=cpu_model(text) if text else platform.processor() or platform.machine(),
        cores=os.cpu_count() or 1,
        system=f"{platform.system()} {platform.release()}",
        python=platform.python_version(),
        numpy=numpy.__version__,
        torch=torch.__version__,
        device=device,
        threads=torch.get_num_threads(),
        load_average=os.getloadavg(),
    )


def exact_command(argv: list[str] | None = None) -> str:
    """The command line as typed, quoted for a POSIX shell.

    The interpreter is named by its base name, and an absolute path by its path from the
    working folder: a published report names no folder of the machine it ran on.
    """
    argv = sys.argv if argv is None else argv
    shown = [os.path.relpath(a) if os.path.isabs(a) else a for a in argv]
    return shlex.join([Path(sys.executable).name, *shown])


def run_header() -> dict:
    """What a report states first: the commit measured, the command and the machine."""
    return {
        "commit": source_commit(),
        "command": exact_command(),
        "machine": describe_machine().line(),
    }


def scene_header(scene: str, seed: int, frames: int, fit: str) -> dict:
    """:func:`run_header` with the emulated scene every fit of the report ran on and its fit."""
    return {**run_header(), "scene": scene, "seed": seed, "frames": frames, "fit": fit}


def measured_line(document: dict) -> str:
    """A report's first line: the commit, machine and command of :func:`run_header`."""
    return f"Measured at {document['commit']} on {document['machine']}: `{document['command']}`."
