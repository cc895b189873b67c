"""Markdown tables of the report: every run, each paper comparison, capture throughput."""

from __future__ import annotations

from benchlib.capture import CaptureResult
from benchlib.numbers import DASH, fmt
from benchlib.paper import Comparison
from benchlib.results import RunRow
from benchlib.targets import CAPTURE_TARGETS
from benchlib.verdicts import ComparisonVerdict

__all__ = ["capture_table", "comparison_lines", "markdown_table", "runs_table"]


def markdown_table(headers: list[str], rows: list[list[str]]) -> str:
    """A GitHub Markdown table; ``|`` inside cells is escaped."""

    def line(cells: list[str]) -> str:
        return "| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |"

    return "\n".join([line(headers), line(["---"] * len(headers)), *map(line, rows)])


def _budget(seconds: float) -> str:
    return f"{seconds / 60:g} min" if seconds >= 60 and seconds % 60 == 0 else f"{seconds:g} s"


def _variant_label(row: RunRow) -> str:
    """The variant, with its seed and the step count it ended at when not the defaults."""
    extras = [f"seed {row.seed}"] * bool(row.seed) + [f"ended at {row.step_cap} steps"] * bool(
        row.step_cap
    )
    return f"{row.variant} ({', '.join(extras)})" if extras else row.variant


def runs_table(rows: list[RunRow]) -> str:
    """Every run at every budget, sorted by session, preset, variant and budget.

    Scores are at the mapped test poses; the registered ones (each test pose refined against
    its own image first) are an extra column.
    """
    ordered = sorted(
        rows, key=lambda r: (r.session, r.preset, r.variant, r.seed, r.step_cap, r.budget_s)
    )
    body = []
    for r in ordered:
        usage = r.process
        body.append(
            [
                r.session,
                r.preset,
                _variant_label(r),
                _budget(r.budget_s),
                str(r.steps),
                fmt(r.train_s, 0),
                r.stopped or DASH,
                fmt(r.rays_per_s, 0),
                fmt(r.hdr_psnr),
                fmt(r.hdr_ssim, 4),
                fmt(r.novel_psnr),
                fmt(r.novel_ssim, 4),
                f"{fmt(r.registered_hdr_psnr)} / {fmt(r.registered_novel_psnr)}",
                fmt(r.render_s_per_view),
                fmt(usage.wall_s if usage else None, 0),
                fmt(usage.cpu_s if usage else None, 0),
                fmt(usage.peak_rss_mb if usage else None, 0),
                r.status,
            ]
        )
    headers = [
        "session",
        "preset",
        "variant",
        "budget",
        "steps",
        "train s",
        "stopped",
        "rays/s",
        "HDR PSNR",
        "HDR SSIM",
        "novel PSNR",
        "novel SSIM",
        "registered HDR / novel PSNR (extra)",
        "render s/view",
        "process wall s",
        "CPU s",
        "peak MB",
        "status",
    ]
    return markdown_table(headers, body)


def _paper_cell(value: tuple[float, float] | None) -> str:
    return DASH if value is None else f"{value[0]:.2f} / {value[1]:.4f}"


def comparison_lines(verdict: ComparisonVerdict, rows: dict[str, RunRow | None]) -> list[str]:
    """The comparison's table (the paper's numbers beside ours) and one line per ordering."""
    comparison: Comparison = verdict.comparison
    headers = [
        "row",
        "paper's name",
        *(f"paper {c} PSNR / SSIM" for c in comparison.columns),
        "ours HDR PSNR / SSIM",
        "ours novel exp. PSNR / SSIM",
        "steps",
        "status",
    ]
    body = []
    for key, (label, values) in comparison.rows.items():
        row = rows.get(key)
        ours = (
            [DASH, DASH, DASH, "not run"]
            if row is None
            else [
                f"{fmt(row.hdr_psnr)} / {fmt(row.hdr_ssim, 4)}",
                f"{fmt(row.novel_psnr)} / {fmt(row.novel_ssim, 4)}",
                str(row.steps),
                row.status,
            ]
        )
        body.append([key, label, *map(_paper_cell, values), *ours])
    lines = [
        markdown_table(headers, body),
        "",
        f"**Paper's ordering here: {verdict.summary}.**",
        "",
    ]
    unmeasured = [c.claim for c in verdict.claims if c.outcome == "not measured"]
    words = {"holds": "holds", "reversed": "**reversed**", "tie": "tie"}
    for claim in verdict.claims:
        if claim.outcome == "not measured":
            continue
        said = claim.claim
        gap = claim.better_db - claim.worse_db
        line = (
            f"- paper: {said.better} > {said.worse} ({said.better_db:.2f} vs "
            f"{said.worse_db:.2f} dB, {said.column}); here: {words[claim.outcome]} "
            f"({claim.better_db:.2f} vs {claim.worse_db:.2f} dB, {gap:+.2f}"
            + (
                f"; means of {claim.seeds} seeds, a tie within {claim.limit_db:.2f})"
                if claim.seeds > 1
                else ")"
            )
        )
        lines.append(line + (f". Measured: {claim.reason}" if claim.reason else ""))
    if unmeasured:
        pairs = ", ".join(f"{c.better} > {c.worse}" for c in unmeasured)
        lines.append(f"- not measured (a run missing or failed): {pairs}")
    return lines


def _digits(figure: str) -> int:
    """Decimals of a capture figure: counts whole, binning seconds to the millisecond."""
    if figure in ("events", "e2e_overflow", "drops"):
        return 0
    return 3 if figure.startswith("binning") else 2


def capture_table(results: list[CaptureResult]) -> str:
    """One line per figure of every capture-side tool, with its target and the tool's memory."""
    body = []
    for result in results:
        usage = result.usage
        memory = fmt(usage.peak_rss_mb if usage else None, 0)
        targets = CAPTURE_TARGETS.get(result.bench.tool, {})
        for name, figure in result.bench.figures.items():
            value, target = result.figures.get(name), targets.get(name)
            shown = DASH if value is None else f"{value:,.{_digits(name)}f}"
            met = target.met(value) if target else None
            goal = target.goal if target else ""
            verdict = "" if met is None else "met" if met else "**missed**"
            body.append([result.bench.tool, figure.label, shown, goal, verdict, memory])
        if result.error:
            body.append([result.bench.tool, "error", result.error, "", "", memory])
    return markdown_table(
        ["tool", "figure", "measured", "target", "verdict", "tool's peak MB"], body
    )
