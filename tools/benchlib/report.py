"""The benchmark report: a Markdown section for BENCHMARKS.md, and the same facts as JSON."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import statistics
from dataclasses import dataclass, field
from pathlib import Path

from benchlib.capture import CaptureResult
from benchlib.fits import SpeedProbe
from benchlib.machine import Machine
from benchlib.matching import common_steps, matched_ladder, matched_row, needs_matching
from benchlib.numbers import DASH, fmt
from benchlib.paper import COMPARISONS, Comparison
from benchlib.plan import METHOD, TABLE4_ROWS, Ladder, Plan
from benchlib.results import RunRow
from benchlib.scene_images import ERROR_GAIN, IMAGES_FOLDER
from benchlib.sessions import SessionOutcome
from benchlib.tables import capture_table, comparison_lines, markdown_table, runs_table
from benchlib.targets import (
    CAPTURE_TARGETS,
    END_TO_END_MIN,
    FAST_OVER_PAPER_RAYS,
    FULL_OVER_BASE_DB,
    FULL_OVER_NO_EVENTS_DB,
    POSES_S,
    RENDER_VIEW_S,
    SCENE_HDR_DB,
    SCENE_NOVEL_DB,
    SCENE_ORACLE_GAP_DB,
    Target,
)
from benchlib.verdicts import TIE_DB, ComparisonVerdict, judge

__all__ = [
    "BenchReport",
    "comparison_rows",
    "comparison_seeds",
    "judge_all",
    "render_markdown",
    "scene_rows",
    "scene_sessions",
    "seed_scores",
    "steps_matched_ladders",
    "target_checks",
    "tie_limit",
    "write_json",
]


POSE_WORDS = {
    "estimated": "estimated from the recording (event-guided COLMAP, as `seecap fit` does)",
    "truth": "the emulator's true camera path (pose estimation not exercised: scores isolate "
    "the trainer)",
}


@dataclass
class BenchReport:
    """Everything one invocation measured."""

    command: str
    machine: Machine
    started_utc: str
    plan: Plan
    poses: str
    commit: str = "unknown"
    wall_s: float = math.nan
    sessions: list[SessionOutcome] = field(default_factory=list)
    rows: list[RunRow] = field(default_factory=list)
    capture: list[CaptureResult] = field(default_factory=list)
    speed: SpeedProbe | None = None
    plot_name: str = "speed_vs_error.png"


def _at(
    rows: list[RunRow], session: str, preset: str, variant: str, budget_s: float
) -> RunRow | None:
    """The default seed's row of that run at the largest budget not above ``budget_s`` (runs
    that ended at a step count are not among them)."""
    found = [
        r
        for r in rows
        if (r.session, r.preset, r.variant, r.seed, r.step_cap) == (session, preset, variant, 0, 0)
        and r.budget_s <= budget_s
    ]
    return max(found, key=lambda r: r.budget_s) if found else None


def comparison_rows(report: BenchReport, axis: str, keys: list[str]) -> dict[str, RunRow | None]:
    """Our run for each row key: a variant on the main session, or a Table 4 session's ``full``."""
    plan = report.plan
    return {
        key: _at(report.rows, session, plan.table_preset, variant, plan.table_budget_s)
        for key, (session, variant) in _row_places(report, axis, keys).items()
    }


def _row_places(report: BenchReport, axis: str, keys: list[str]) -> dict[str, tuple[str, str]]:
    """``(session, variant)`` behind each row key of a comparison on ``axis``."""
    main = report.plan.sessions[0].key
    return {k: (TABLE4_ROWS[k], METHOD) if axis == "session" else (main, k) for k in keys}


def comparison_seeds(report: BenchReport, axis: str, keys: list[str]) -> dict[str, list[float]]:
    """HDR PSNR of every seed's scored run behind each row key, at the table budget."""
    plan = report.plan
    where = _row_places(report, axis, keys)
    return {
        key: [
            r.hdr_psnr
            for r in sorted(report.rows, key=lambda r: r.seed)
            if (r.session, r.variant) == (session, variant)
            and (r.preset, r.budget_s, r.step_cap) == (plan.table_preset, plan.table_budget_s, 0)
            and r.ok
        ]
        for key, (session, variant) in where.items()
    }


def seed_scores(report: BenchReport) -> list[tuple[int, float]]:
    """``(seed, HDR PSNR)`` of the table preset's ``full`` at the table budget, every seed run."""
    plan = report.plan
    return sorted(
        (r.seed, r.hdr_psnr)
        for r in report.rows
        if (r.session, r.preset, r.variant, r.budget_s, r.step_cap)
        == (plan.sessions[0].key, plan.table_preset, METHOD, plan.table_budget_s, 0)
        and r.ok
    )


def tie_limit(report: BenchReport) -> float:
    """Largest minus smallest HDR PSNR over the seeds when two or more ran, else TIE_DB."""
    scores = [score for _, score in seed_scores(report)]
    return max(scores) - min(scores) if len(scores) > 1 else TIE_DB


def judge_all(report: BenchReport) -> list[ComparisonVerdict]:
    """Every paper comparison judged on the runs measured so far: where both sides of an
    ordering ran several seeds, their means, a tie within twice the standard error of the
    difference; else the default seeds' runs, a tie within ``full``'s seed spread."""
    tie_db = tie_limit(report)
    return [
        judge(
            c,
            comparison_rows(report, c.axis, list(c.rows)),
            tie_db,
            comparison_seeds(report, c.axis, list(c.rows)),
        )
        for c in COMPARISONS
    ]


def _timed_rows(report: BenchReport, comparison: Comparison) -> tuple[dict, int]:
    """The comparison's time-matched rows and the fewest steps any of them trained."""
    rows = comparison_rows(report, comparison.axis, list(comparison.rows))
    return rows, common_steps(rows.values())


def steps_matched_ladders(report: BenchReport) -> list[Ladder]:
    """The runs that match every comparison on steps, each once: every row that trained past
    its comparison's fewest steps, ended at that count."""
    ladders = []
    for comparison in COMPARISONS:
        rows, steps = _timed_rows(report, comparison)
        for row in rows.values():
            ladder = matched_ladder(row, steps) if needs_matching(row, steps) else None
            if ladder and ladder not in ladders:
                ladders.append(ladder)
    return ladders


def _steps_lines(report: BenchReport, by_time: ComparisonVerdict) -> list[str]:
    """The comparison matched on steps, and each ordering that reads otherwise than on time."""
    timed, steps = _timed_rows(report, by_time.comparison)
    rows = {key: matched_row(row, report.rows, steps) for key, row in timed.items()}
    by_steps = judge(by_time.comparison, rows, tie_limit(report))
    if by_steps.summary == "not measured":
        return []
    again = [key for key, row in timed.items() if needs_matching(row, steps)]
    lines = [
        f"Matched on steps: every row at {steps} steps, the fewest any row trained in "
        f"{fmt(report.plan.table_budget_s, 0)} s ({', '.join(again) or 'no row'} trained "
        "again to end there; the default seed, a tie within the seed spread): "
        f"**{by_steps.summary}**.",
        "",
    ]
    on_time = {(c.claim.better, c.claim.worse): c.outcome for c in by_time.claims}
    for c in by_steps.claims:
        before = on_time[c.claim.better, c.claim.worse]
        if c.outcome != before and "not measured" not in (c.outcome, before):
            lines.append(
                f"- {c.claim.better} > {c.claim.worse}: {c.outcome} on steps "
                f"({c.better_db:.2f} vs {c.worse_db:.2f} dB), {before} on time"
            )
    if len(lines) == 2:
        lines.append("Every ordering measured both ways reads the same on steps as on time.")
    return [*lines, ""]


def _seed_line(report: BenchReport) -> str:
    scores = seed_scores(report)
    if len(scores) < 2:
        return (
            f"One run per row: differences under {TIE_DB:g} dB count as ties (the seed "
            "spread was not measured)."
        )
    listed = ", ".join(f"seed {seed}: {fmt(score)}" for seed, score in scores)
    return (
        f"Seed spread: `full` at this budget scored {listed} dB with nothing but the seed "
        f"changed, a spread of {fmt(tie_limit(report))} dB. Rows that ran several seeds are "
        "compared by their means, an ordering only where the difference exceeds twice its "
        "standard error; a row with one run is compared within that spread."
    )


def _check(name: str, value: float | None, target: Target) -> list[str]:
    met = target.met(value)
    verdict = "not measured" if met is None else "met" if met else "**missed**"
    return [name, fmt(value), target.goal, verdict]


def target_checks(report: BenchReport) -> list[list[str]]:
    """Every target read from the runs: the trainer's margins and speed, rendering, then each
    scene's (:func:`scene_checks`) and the capture side's (:func:`capture_checks`)."""
    rows = comparison_rows(report, "variant", [METHOD, "base", "no-events"])
    full = rows[METHOD]
    checks = []
    for other, target in (("base", FULL_OVER_BASE_DB), ("no-events", FULL_OVER_NO_EVENTS_DB)):
        ok = full and rows[other] and full.ok and rows[other].ok
        value = full.hdr_psnr - rows[other].hdr_psnr if ok else None
        checks.append(_check(f"full − {other}, HDR PSNR dB", value, target))
    ratio = report.speed.rays_per_s.get("fast_over_paper") if report.speed else None
    checks.append(_check("rays/s, fast ÷ paper (same process)", ratio, FAST_OVER_PAPER_RAYS))
    return checks + scene_checks(report) + capture_checks(report.capture)


def _end_to_end_s(report: BenchReport, session: str, poses_s: float) -> float | None:
    """Poses plus every process of the session's ``full`` runs (training, renders, scores)."""
    walls = [
        r.process.wall_s
        for r in report.rows
        if (r.session, r.variant, r.seed, r.step_cap) == (session, METHOD, 0, 0)
        and r.preset == report.plan.table_preset
        and r.process is not None
    ]
    return poses_s + sum(walls) if walls and math.isfinite(poses_s) else None


def _meets_scene_targets(full: RunRow, gap: float | None) -> bool:
    """Whether ``full``'s HDR and novel scores and its oracle gap meet the scene targets."""
    return bool(
        SCENE_HDR_DB.met(full.hdr_psnr)
        and SCENE_NOVEL_DB.met(full.novel_psnr)
        and SCENE_ORACLE_GAP_DB.met(gap)
    )


def scene_checks(report: BenchReport) -> list[list[str]]:
    """Per scene: HDR and novel-exposure PSNR, the oracle gap, a view's render time, the pose
    time and the time end to end from the recording, each against its target."""
    checks = []
    for scene, full, oracle, outcome in _scene_runs(report):
        poses_s = outcome.poses_s if outcome else math.nan
        end_to_end = _end_to_end_s(report, scene, poses_s)
        hdr, novel = (full.hdr_psnr, full.novel_psnr) if full.ok else (None, None)
        gap = oracle.hdr_psnr - full.hdr_psnr if oracle and full.ok else None
        render = full.render_s_per_view if math.isfinite(full.render_s_per_view) else None
        for name, value, target in (
            ("full HDR PSNR dB", hdr, SCENE_HDR_DB),
            ("full novel-exposure PSNR dB", novel, SCENE_NOVEL_DB),
            ("oracle − full HDR PSNR dB", gap, SCENE_ORACLE_GAP_DB),
            ("full: render one view, s", render, RENDER_VIEW_S),
            ("poses from the recording, s", poses_s if math.isfinite(poses_s) else None, POSES_S),
            (
                "end to end from the recording (poses, then every process of full's runs with "
                "their renders and scores), min",
                None if end_to_end is None else end_to_end / 60,
                END_TO_END_MIN,
            ),
        ):
            checks.append(_check(f"{scene}: {name}", value, target))
    return checks


def capture_checks(results: list[CaptureResult]) -> list[list[str]]:
    """Every capture-side figure that has a target: decoding, USB words, recording."""
    return [
        _check(
            f"{result.bench.tool}: {result.bench.figures[name].label}",
            result.figures.get(name),
            target,
        )
        for result in results
        for name, target in CAPTURE_TARGETS.get(result.bench.tool, {}).items()
    ]


def _turn(angles: list[float]) -> str:
    """``median / max`` of the held-out poses' registration turns, degrees, or ``-``."""
    if not angles:
        return DASH
    return f"{fmt(statistics.median(angles))} / {fmt(max(angles))}"


def _scene_runs(report: BenchReport):
    """``(session, full, oracle or None, outcome or None)`` of every session whose ``full`` ran
    at the top budget (the oracle only when it ran there too and was scored)."""
    plan = report.plan
    top = max((b for ladder in plan.ladders for b in ladder.budgets_s), default=0.0)
    outcomes = {s.spec.key: s for s in report.sessions}
    for spec in plan.sessions:
        full = _at(report.rows, spec.key, plan.table_preset, METHOD, top)
        oracle = _at(report.rows, spec.key, plan.table_preset, "oracle", top)
        if full is None or full.budget_s != top:
            continue
        oracle = oracle if oracle and oracle.budget_s == top and oracle.ok else None
        yield spec.key, full, oracle, outcomes.get(spec.key)


def scene_rows(report: BenchReport) -> list[list[str]]:
    """Per scene at the top budget: ``full`` and ``oracle``, their gap, and what it is made of.

    The columns that explain the gap: the held-out score with each test pose refined against
    its own image (an extra: what the mapped poses' error costs), the learned response's
    distance from the true one, and the session's pose errors.
    """
    body = []
    for key, full, oracle, outcome in _scene_runs(report):
        ok = full.ok
        gap = oracle.hdr_psnr - full.hdr_psnr if oracle and ok else None
        met = ok and _meets_scene_targets(full, gap)
        body.append(
            [
                key,
                fmt(full.hdr_psnr if ok else None),
                fmt(full.novel_psnr if ok else None),
                fmt(oracle.hdr_psnr if oracle else None),
                fmt(oracle.novel_psnr if oracle else None),
                fmt(gap),
                fmt(full.registered_hdr_psnr if ok else None),
                _turn(full.test_pose_turn_deg if ok else []),
                fmt(full.crf_rms if ok else None, 3),
                fmt(outcome.rotation_error_deg if outcome else None),
                fmt(outcome.centre_error if outcome else None, 3),
                str(full.steps),
                "met" if met else "**missed**" if ok else full.status,
            ]
        )
    return body


SCENE_HEADERS = [
    "session",
    "full HDR",
    "full novel",
    "oracle HDR",
    "oracle novel",
    "oracle − full HDR",
    "full HDR, registered (extra)",
    "test poses turned by registering, median / max °",
    "CRF RMS",
    "rotation error °",
    "centre error / extent",
    "full steps",
    "targets ("
    + ", ".join(t.in_words for t in (SCENE_HDR_DB, SCENE_NOVEL_DB, SCENE_ORACLE_GAP_DB))
    + ")",
]


def _session_lines(report: BenchReport) -> list[str]:
    body = []
    for s in report.sessions:
        spec = s.spec
        made = f"{fmt(s.record_s, 0)} s" + (" (cached)" if s.cached else "")
        body.append(
            [
                spec.key,
                spec.scene,
                str(spec.seed),
                f"{spec.exposure_us / 1e6:g}",
                f"{(spec.gain_exposure_us or spec.exposure_us) / 1e6:g}",
                f"x{spec.noise_scale:g}",
                str(s.frames),
                f"{s.events:,}",
                made,
                fmt(s.poses_s, 0),
                f"{s.registered} of {s.latent}",
                fmt(s.rotation_error_deg),
                fmt(s.centre_error, 3),
                s.error or "ready",
            ]
        )
    headers = [
        "session",
        "scene",
        "seed",
        "exposure s",
        "gain set by s",
        "DVS noise",
        "frames",
        "events",
        "recorded in",
        f"poses ({report.poses}) s",
        "poses registered",
        "rotation error °",
        "centre error / extent",
        "status",
    ]
    return [markdown_table(headers, body)]


def scene_sessions(report: BenchReport) -> dict[str, Path]:
    """The folder of every session of the scene table (its ``full`` ran at the top budget)."""
    return {key: outcome.folder for key, _, _, outcome in _scene_runs(report) if outcome}


def _scene_image_lines(report: BenchReport) -> list[str]:
    """Links to each scene's side-by-side image (:mod:`benchlib.scene_images`)."""
    keys = list(scene_sessions(report))
    if not keys:
        return []
    folder = Path(report.plot_name).parent / IMAGES_FOLDER
    lines = [
        "The first held-out view of each scene, as it is scored (each render times its global "
        "scale, tone-mapped relative to the truth's peak): truth, `full`, `oracle` (grey when "
        f"it did not run) and `full`'s error, magnified {ERROR_GAIN:g}x.",
        "",
    ]
    for key in keys:
        image = folder / f"{key}.png"
        lines += [f"{key}:", "", f"![{key}: truth, full, oracle, error]({image})", ""]
    return lines


def _speed_lines(speed: SpeedProbe | None) -> list[str]:
    if speed is None:
        return ["Not measured (the main session was not ready)."]
    if speed.error:
        return [f"Not measured: {speed.error}"]
    body = [
        [name.replace("_over_", " ÷ "), fmt(value, 0 if "_over_" not in name else 1)]
        for name, value in speed.rays_per_s.items()
    ]
    memory = fmt(speed.usage.peak_rss_mb if speed.usage else None, 0)
    return [
        "Each preset trained a few steps on the main session's data in one process "
        "(`tools/bench_fit.py`'s `speed_table`: every preset first trains untimed warm-up "
        "steps, the CPU presets through two occupancy-grid refreshes as a fit does in its "
        "first seconds, then the presets take turns over three timed rounds; no CRF warm "
        "start, no held-out pixels, no renders; the paper preset with a smaller batch and a "
        f"tenth of the steps); that process peaked at {memory} MB.",
        "",
        markdown_table(["preset", "rays/s"], body),
    ]


def _fit_cores(command: str) -> str:
    """How the command's fits shared the machine, read from its options."""
    words = command.split()
    if "--ray" in words:
        return "Ray tasks side by side, one core and one torch thread each"
    if "--threads" in words[:-1]:
        return f"one at a time, {words[words.index('--threads') + 1]} torch threads each"
    return "one at a time, with every core"


def _reuse_line(rows: list[RunRow]) -> str:
    reused = sum(row.reused for row in rows)
    if not reused:
        return f"All {len(rows)} rungs were trained by this invocation."
    return (
        f"{reused} of {len(rows)} rungs were read back from an earlier invocation of the same "
        "command (kept metrics and checkpoint found; their process figures are from that "
        f"invocation), {len(rows) - reused} trained by this one."
    )


def render_markdown(report: BenchReport) -> str:
    """The report as a Markdown section (``## Speed against error`` and its subsections)."""
    plan = report.plan
    views = f"{plan.views[0]} training + {plan.views[1]} held-out views"
    lines = [
        "## Speed against error",
        "",
        f"Command: `{report.command}` ({'quick' if plan.quick else 'full'} mode) at commit "
        f"{report.commit[:12]}, started {report.started_utc}, {report.wall_s / 60:.1f} min wall "
        "for this invocation.",
        "",
        f"Machine: {report.machine.line()}.",
        "",
        f"Every number below is regenerated by that command. Sessions are emulated DAVIS346 "
        f"recordings ({views}, b = 4), cached under the output folder; poses: "
        f"{POSE_WORDS.get(report.poses, report.poses)}. "
        f"Each training run is its own process ({_fit_cores(report.command)}); peak memory is "
        "that process's maximum resident set. A budget ladder trains one run and scores it at "
        "each budget on the way (resuming its checkpoint), so train s and steps are cumulative.",
        "",
        *(f"Note: {note}." for note in plan.notes),
        "",
        _reuse_line(report.rows),
        "",
        "### Sessions",
        "",
        *_session_lines(report),
        "",
        "### Every preset and variant against wall time",
        "",
        runs_table(report.rows),
        "",
        f"![speed against error]({report.plot_name})",
        "",
        "### Every scene: full beside oracle",
        "",
        f"Preset {plan.table_preset} at the top budget, from the recording with its own poses; "
        "PSNR in dB at the true test poses mapped by the training cameras' similarity, HDR after "
        "one global scale. `full HDR, registered (extra)` refines each test pose against its "
        "own test image first: not a headline, its distance to `full HDR` is what the mapped "
        "poses' error costs. The oracle is trained on "
        "sharp linear HDR at the true poses, so `oracle − full` is what blur, clipping, the "
        "sensor models and the poses leave on the table.",
        "",
        markdown_table(SCENE_HEADERS, scene_rows(report)),
        "",
        *_scene_image_lines(report),
        "### The paper's comparisons on our data",
        "",
        f"Preset {plan.table_preset}, budget {plan.table_budget_s:g} s; ours are tone-mapped HDR "
        "and novel-exposure scores on the held-out views. An ordering is checked on HDR PSNR, "
        "matched on wall time (the budget) and then on training steps.",
        "",
        _seed_line(report),
        "",
    ]
    for verdict in judge_all(report):
        keys = list(verdict.comparison.rows)
        rows = comparison_rows(report, verdict.comparison.axis, keys)
        lines += [
            f"#### {verdict.comparison.title}",
            "",
            verdict.comparison.ours,
            "",
            *comparison_lines(verdict, rows),
            "",
            *_steps_lines(report, verdict),
        ]
    lines += [
        "### Rays per second of each preset",
        "",
        *_speed_lines(report.speed),
        "",
        "### Targets",
        "",
        "Every goal, computed from the runs above: the trainer's margins and speed, each "
        "scene's scores, pose time and end-to-end time, and the capture side's figures.",
        "",
        markdown_table(["target", "measured", "goal", "verdict"], target_checks(report)),
        "",
        "### Capture-side throughput",
        "",
        capture_table(report.capture),
        "",
    ]
    return "\n".join(lines)


def write_json(report: BenchReport, path: Path) -> None:
    """Every measured value (runs, verdicts, capture output lines) as JSON.

    Paths under the working folder are written relative to it, so the file can be published.
    """

    def default(value):
        if isinstance(value, Path):
            return str(value)
        if dataclasses.is_dataclass(value):
            return dataclasses.asdict(value)
        return repr(value)

    payload = dataclasses.asdict(report)
    payload["verdicts"] = [
        {**dataclasses.asdict(v), "summary": v.summary} for v in judge_all(report)
    ]
    payload["targets"] = target_checks(report)
    text = json.dumps(payload, indent=1, default=default, allow_nan=True)
    path.write_text(text.replace(f"{Path.cwd()}{os.sep}", "") + "\n")
