"""Whether the paper's orderings hold on our runs, and the measured differences where not."""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass

from benchlib.numbers import fmt
from benchlib.paper import Claim, Comparison, paper_claims
from benchlib.results import RunRow

__all__ = ["TIE_DB", "ClaimVerdict", "ComparisonVerdict", "explain_difference", "judge"]

TIE_DB = 0.05
"""HDR PSNR differences smaller than this are ties when the seed spread was not measured: the
report prints 0.01 dB, and a gap this small says nothing about an ordering measured from one
run per row."""


@dataclass(frozen=True)
class ClaimVerdict:
    """One paper ordering checked on our runs.

    Attributes:
        claim: the paper's ordering.
        outcome: ``holds``, ``reversed``, ``tie`` (within ``limit_db``) or ``not measured``
            (a run missing or failed).
        better_db: our HDR PSNR of the row the paper ranks higher, dB (the mean over its seeds
            when several ran).
        worse_db: our HDR PSNR of the row the paper ranks lower, dB (likewise).
        reason: measured per-component differences (filled unless it holds or is unmeasured).
        seeds: runs behind each side's score (1: the default seed's run alone).
        limit_db: the difference under which the ordering is a tie: twice the standard error of
            the difference of the means when both sides ran several seeds, else the fixed limit.
    """

    claim: Claim
    outcome: str
    better_db: float = math.nan
    worse_db: float = math.nan
    reason: str = ""
    seeds: int = 1
    limit_db: float = TIE_DB


@dataclass(frozen=True)
class ComparisonVerdict:
    """Every ordering of one comparison, with a one-line summary; ``tie_db`` is the tie limit."""

    comparison: Comparison
    claims: tuple[ClaimVerdict, ...]
    tie_db: float = TIE_DB

    @property
    def summary(self) -> str:
        """``holds``, ``does not hold``, ``undecided`` or ``not measured``, with the counts."""
        counts = {
            o: sum(c.outcome == o for c in self.claims)
            for o in ("holds", "reversed", "tie", "not measured")
        }
        judged = len(self.claims) - counts["not measured"]
        if judged == 0:
            return "not measured"
        seeded = all(c.seeds > 1 for c in self.claims if c.outcome == "tie")
        tie_words = (
            "within twice the standard error of the difference"
            if seeded
            else f"within {self.tie_db:.2f} dB"
        )
        extra = [
            f"{counts[o]} {word}"
            for o, word in (
                ("tie", tie_words),
                ("not measured", "not measured"),
            )
            if counts[o]
        ]
        tail = f" ({'; '.join(extra)})" if extra else ""
        if counts["reversed"]:
            return f"does not hold: {counts['reversed']} of {judged} orderings reversed{tail}"
        if counts["tie"]:
            return f"undecided: {counts['holds']} of {judged} orderings as in the paper{tail}"
        return f"holds: all {judged} orderings as in the paper{tail}"


def _pair(a: float, b: float) -> str:
    return f"{fmt(a)} vs {fmt(b)}"


def explain_difference(better: RunRow, worse: RunRow) -> str:
    """Measured differences between two runs, per component, for a reversed ordering.

    Names the training effort (steps, seconds, rays per second), the LDR PSNR difference at every
    test exposure (dark to bright; only when both runs were tested at the same exposures), the fit
    to the blurry input frames and the HDR score before scale alignment; each as ``better`` vs
    ``worse`` in the paper's ranking.
    """
    parts = [
        f"training {better.steps} vs {worse.steps} steps in {fmt(better.train_s, 0)} vs "
        f"{fmt(worse.train_s, 0)} s ({fmt(better.rays_per_s, 0)} vs {fmt(worse.rays_per_s, 0)} "
        "rays/s)"
    ]
    same_exposures = [e for e, _ in better.ldr_psnr] == [e for e, _ in worse.ldr_psnr]
    if better.ldr_psnr and same_exposures:
        deltas = ", ".join(
            f"{e:g} s {a - b:+.2f}"
            for (e, a), (_, b) in zip(better.ldr_psnr, worse.ldr_psnr, strict=True)
        )
        parts.append(f"LDR PSNR difference per test exposure: {deltas} dB")
    if math.isfinite(better.fit_psnr) or math.isfinite(worse.fit_psnr):  # none before 1st eval
        parts.append(f"fit to the blurry input frames {_pair(better.fit_psnr, worse.fit_psnr)} dB")
    parts.append(
        "HDR PSNR before scale alignment "
        f"{_pair(better.hdr_unaligned_psnr, worse.hdr_unaligned_psnr)} dB"
    )
    return "; ".join(parts)


def _mean_and_variance(scores: list[float]) -> tuple[float, float]:
    """Mean and the variance of the mean (sample variance over n)."""
    return statistics.fmean(scores), statistics.variance(scores) / len(scores)


def judge(
    comparison: Comparison,
    rows: dict[str, RunRow | None],
    tie_db: float = TIE_DB,
    seeds: dict[str, list[float]] | None = None,
) -> ComparisonVerdict:
    """Check each of the paper's orderings on our HDR PSNR.

    Args:
        comparison: the paper's comparison.
        rows: our default-seed run for each row key of the comparison (None or failed: not
            measured).
        tie_db: differences below this are ties when a side ran one seed only.
        seeds: each row key's HDR PSNR over every seed that ran (the default's included); when
            both sides of an ordering have two or more, their means are compared and a
            difference within twice its standard error is a tie.
    """
    seeds = seeds or {}
    verdicts = []
    for claim in paper_claims(comparison):
        better, worse = rows.get(claim.better), rows.get(claim.worse)
        if better is None or worse is None or not (better.ok and worse.ok):
            verdicts.append(ClaimVerdict(claim, "not measured"))
            continue
        ours = seeds.get(claim.better, []), seeds.get(claim.worse, [])
        if min(len(scores) for scores in ours) >= 2:
            (high, high_var), (low, low_var) = map(_mean_and_variance, ours)
            limit, runs = 2 * math.sqrt(high_var + low_var), min(map(len, ours))
        else:
            high, low, limit, runs = better.hdr_psnr, worse.hdr_psnr, tie_db, 1
        gap = high - low
        outcome = "tie" if abs(gap) <= limit else "holds" if gap > 0 else "reversed"
        reason = "" if outcome == "holds" else explain_difference(better, worse)
        verdicts.append(ClaimVerdict(claim, outcome, high, low, reason, runs, limit))
    return ComparisonVerdict(comparison, tuple(verdicts), tie_db)
