"""The sharing benchmark's markdown section, rendered from its JSON document alone."""

from __future__ import annotations

from benchlib.machine import measured_line
from benchlib.targets import BUSY_SHARE

__all__ = ["SHARING_CASES", "sharing_report"]

SHARING_CASES = {
    "alone": "the machine to itself, threads chosen by the fit",
    "busy-auto": "beside one busy process, threads chosen by the fit (from the cores it leaves)",
    "busy-all": "beside one busy process, one thread per core asked for (`--threads` = cores)",
}
"""Each fit of the benchmark, by name, and what it is."""


def _row(name: str, case: dict, alone: dict | None) -> str:
    if case.get("error"):
        return f"| {name} | failed: {case['error'][:80]} | | | |"
    share = case["steps_per_s"] / alone["steps_per_s"] if alone else None
    shown = "-" if share is None else f"{share:.2f}"
    return (
        f"| {name} | {case['threads']} | {case['steps']} in {case['training_s']:.1f} s | "
        f"{case['steps_per_s']:.2f} | {shown} |"
    )


def sharing_report(document: dict) -> str:
    """Markdown: each fit's threads and training speed, and its share of the speed alone."""
    cases = document["cases"]
    alone = cases.get("alone")
    alone = None if alone is None or alone.get("error") else alone
    auto = cases.get("busy-auto", {})
    verdict = "not measured"
    if alone and not auto.get("error") and "steps_per_s" in auto:
        share = auto["steps_per_s"] / alone["steps_per_s"]
        verdict = f"{share:.2f} ({'met' if BUSY_SHARE.met(share) else 'missed'})"
    lines = [
        measured_line(document),
        "",
        f"Scene `{document['scene']}`, seed {document['seed']}, {document['frames']} frames, "
        f"calibrated and posed once; each fit `{document['fit']}`, one after another. The busy "
        f"process is `{document['busy']}`. Steps per second of the training alone (the fit's "
        "`metrics.json`). Target: beside one busy process, at least "
        f"{BUSY_SHARE.limit:.1f} of the speed alone with the threads the fit chooses: {verdict}.",
        "",
        "| fit | threads | steps in training time | steps/s | share of alone |",
        "|---|---|---|---|---|",
    ]
    lines += [_row(name, cases[name], alone) for name in SHARING_CASES if name in cases]
    lines += [""] + [f"* **{name}**: {text}." for name, text in SHARING_CASES.items()]
    return "\n".join(lines)
