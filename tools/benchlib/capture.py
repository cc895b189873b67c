"""Capture-side throughput: the existing ``tools/bench_*.py`` run as child processes, parsed."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from benchlib.results import ProcessUsage
from benchlib.runner import python_command, run_measured

__all__ = [
    "CAPTURE_BENCHES",
    "CaptureBench",
    "CaptureResult",
    "meets",
    "parse_output",
    "run_capture_bench",
]

NUMBER = r"([-+]?\d[\d,]*(?:\.\d+)?)"


@dataclass(frozen=True)
class CaptureBench:
    """One capture-side benchmark tool and the figures read from its output.

    Attributes:
        tool: script under ``tools/``.
        figures: figure name -> (label with unit, regular expression whose group 1 is the number).
        targets: figure name -> (comparison ``>=``, ``<`` or ``==``, value) the figure must meet.
    """

    tool: str
    figures: dict[str, tuple[str, str]]
    targets: dict[str, tuple[str, float]] = field(default_factory=dict)


CAPTURE_BENCHES = (
    CaptureBench("bench_decode.py", {
        "events": ("events in the file", rf"file: {NUMBER} events"),
        "ours_mev_s": ("ours, M events/s", rf"ours:\s+{NUMBER} M events/s"),
        "dv_mev_s": ("dv-processing, M events/s", rf"dv-processing:\s+{NUMBER} M events/s"),
        "ratio": ("ours / dv-processing", rf"ratio ours / dv-processing: {NUMBER}"),
    }),
    CaptureBench("bench_usb.py", {
        "decoder_mwords_s": ("word decoder, M words/s", rf"s: {NUMBER} M words/s"),
        "decoder_mev_s": ("word decoder, M events/s", rf"M words/s, {NUMBER} M events/s"),
        "e2e_mev_s": ("end to end at 12 M events/s, M events/s received",
                      rf"events \({NUMBER} M events/s of stream time"),
        "e2e_lag_ms": ("end to end, largest lag, ms", rf"max lag {NUMBER} ms"),
        "e2e_overflow": ("end to end, host queue overflow, packets",
                         rf"host queue overflow {NUMBER} packets"),
    }, {"decoder_mwords_s": (">=", 50.0), "e2e_overflow": ("==", 0.0)}),
    CaptureBench("bench_record.py", {
        "binning_b4_s": ("binning 1 M events, b=4, s", rf"b=4: {NUMBER} s"),
        "binning_b6_s": ("binning 1 M events, b=6, s", rf"b=6: {NUMBER} s"),
        "capacity_mev_s": ("recorder capacity (unpaced), M events/s", rf"capacity.*?: {NUMBER} M"),
        "recorded_mev_s": ("recording paced at 12 M events/s, M events/s",
                           rf"frames, {NUMBER} M events/s over"),
        "drops": ("recording, dropped events", rf"drops: {NUMBER} events"),
    }, {"binning_b4_s": ("<", 0.5), "binning_b6_s": ("<", 0.5), "drops": ("==", 0.0)}),
)
"""The capture-side benchmarks, in report order."""


@dataclass
class CaptureResult:
    """One tool's run: its figures, the lines it printed, and what the process cost."""

    bench: CaptureBench
    command: list[str]
    usage: ProcessUsage | None = None
    figures: dict[str, float] = field(default_factory=dict)
    lines: list[str] = field(default_factory=list)
    error: str = ""


def meets(value: float, target: tuple[str, float]) -> bool:
    """Whether ``value`` satisfies ``(comparison, limit)``."""
    comparison, limit = target
    return {">=": value >= limit, "<": value < limit, "==": value == limit}[comparison]


def parse_output(bench: CaptureBench, text: str) -> dict[str, float]:
    """The figures found in a tool's output (missing ones are left out)."""
    figures = {}
    for name, (_, pattern) in bench.figures.items():
        match = re.search(pattern, text)
        if match:
            figures[name] = float(match.group(1).replace(",", ""))
    return figures


def run_capture_bench(bench: CaptureBench, tools_dir: Path, log_dir: Path, quick: bool,
                      timeout_s: float = 1800.0) -> CaptureResult:
    """Run one tool (``--quick`` when asked) in its own process and read its figures."""
    command = python_command(str(tools_dir / bench.tool), *(["--quick"] if quick else []))
    result = CaptureResult(bench, command)
    log = log_dir / f"capture-{Path(bench.tool).stem}.log"
    result.usage = run_measured(command, log, cwd=tools_dir.parent, timeout_s=timeout_s)
    text = log.read_text(errors="replace")
    result.lines = [line for line in text.splitlines() if line.strip()]
    result.figures = parse_output(bench, text)
    missing = sorted(set(bench.figures) - set(result.figures))
    if missing:
        tail = result.lines[-1] if result.lines else "no output"
        result.error = (f"exit {result.usage.returncode}; figures not found: "
                        f"{', '.join(missing)}; last line: {tail}")
    return result
