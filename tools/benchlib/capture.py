"""Capture-side throughput: each ``tools/bench_*.py`` tool's ``run`` in a child process."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from benchlib.results import ProcessUsage
from benchlib.runner import python_command, run_measured
from benchlib.tool_result import RESULT_PREFIX

__all__ = [
    "CAPTURE_BENCHES",
    "CaptureBench",
    "CaptureResult",
    "Figure",
    "figures_from",
    "read_result",
    "run_capture_bench",
]


@dataclass(frozen=True)
class Figure:
    """One number of a tool's result, as the report shows it.

    Attributes:
        label: name with unit.
        key: where it is in the tool's result dict, nested keys joined by dots.
        scale: factor from the result's unit to the label's.
    """

    label: str
    key: str
    scale: float = 1.0


@dataclass(frozen=True)
class CaptureBench:
    """One capture-side benchmark tool and the figures read from its ``run`` result (the
    targets of some are :data:`benchlib.targets.CAPTURE_TARGETS`).

    Attributes:
        tool: script under ``tools/`` with a ``run(quick) -> dict``.
        figures: figure name -> :class:`Figure`.
    """

    tool: str
    figures: dict[str, Figure]


CAPTURE_BENCHES = (
    CaptureBench(
        "bench_decode.py",
        {
            "events": Figure("events in the file", "events"),
            "ours_mev_s": Figure("ours, M events/s", "ours_ev_s", 1e-6),
            "python_lz4_mev_s": Figure(
                "ours with python-lz4 only, M events/s", "python_lz4_ev_s", 1e-6
            ),
            "dv_mev_s": Figure("dv-processing, M events/s", "dv_ev_s", 1e-6),
            "ratio": Figure("ours / dv-processing", "ratio"),
            "python_lz4_ratio": Figure(
                "ours with python-lz4 only / dv-processing", "python_lz4_ratio"
            ),
        },
    ),
    CaptureBench(
        "bench_usb.py",
        {
            "decoder_mwords_s": Figure("word decoder, M words/s", "decoder.mwords_s"),
            "decoder_mev_s": Figure("word decoder, M events/s", "decoder.mevents_s"),
            "e2e_mev_s": Figure(
                "end to end at 12 M events/s, M events/s received", "end_to_end.mevents_s"
            ),
            "e2e_lag_ms": Figure("end to end, largest lag, ms", "end_to_end.lag_max_s", 1e3),
            "e2e_overflow": Figure(
                "end to end, host queue overflow, packets", "end_to_end.packets_lost"
            ),
        },
    ),
    CaptureBench(
        "bench_record.py",
        {
            "binning_b4_s": Figure("binning 1 M events, b=4, s", "binning_s.b4"),
            "binning_b6_s": Figure("binning 1 M events, b=6, s", "binning_s.b6"),
            "capacity_mev_s": Figure(
                "recorder capacity (unpaced), M events/s", "capacity.events_per_s", 1e-6
            ),
            "recorded_mev_s": Figure(
                "recording paced at 12 M events/s, M events/s", "recording.events_per_s", 1e-6
            ),
            "drops": Figure("recording, dropped events", "recording.dropped_events"),
        },
    ),
)
"""The capture-side benchmarks, in report order."""


@dataclass
class CaptureResult:
    """One tool's run: its figures, its whole result dict, and what the process cost."""

    bench: CaptureBench
    command: list[str]
    usage: ProcessUsage | None = None
    figures: dict[str, float] = field(default_factory=dict)
    result: dict = field(default_factory=dict)
    error: str = ""


def read_result(text: str) -> dict | None:
    """The result dict of a :mod:`benchlib.tool_result` child's output (None if absent)."""
    for line in reversed(text.splitlines()):
        if line.startswith(RESULT_PREFIX):
            return json.loads(line[len(RESULT_PREFIX) :])
    return None


def figures_from(bench: CaptureBench, result: dict) -> dict[str, float]:
    """The figures found in a tool's result, scaled to their labels' units (missing left out)."""
    figures = {}
    for name, figure in bench.figures.items():
        value = result
        for key in figure.key.split("."):
            value = value.get(key) if isinstance(value, dict) else None
        if isinstance(value, int | float):
            figures[name] = float(value) * figure.scale
    return figures


def run_capture_bench(
    bench: CaptureBench, tools_dir: Path, log_dir: Path, quick: bool, timeout_s: float = 1800.0
) -> CaptureResult:
    """Run one tool's ``run`` (quick when asked) in its own process and read its figures."""
    command = python_command(
        "-m", "benchlib.tool_result", Path(bench.tool).stem, *(["--quick"] if quick else [])
    )
    result = CaptureResult(bench, command)
    log = log_dir / f"capture-{Path(bench.tool).stem}.log"
    result.usage = run_measured(command, log, cwd=tools_dir, timeout_s=timeout_s)
    text = log.read_text(errors="replace")
    result.result = read_result(text) or {}
    result.figures = figures_from(bench, result.result)
    missing = sorted(set(bench.figures) - set(result.figures))
    if missing:
        lines = [line for line in text.splitlines() if line.strip()]
        tail = lines[-1] if lines else "no output"
        result.error = (
            f"exit {result.usage.returncode}; figures not found: "
            f"{', '.join(missing)}; last line: {tail[:200]}"
        )
    return result
