import math

from benchlib.paper import TABLE_9_LOWPASS
from benchlib.results import RunRow
from benchlib.verdicts import explain_difference, judge


def row(variant, hdr, **kwargs):
    values = dict(
        steps=100,
        train_s=30.0,
        rays_per_s=1000.0,
        hdr_ssim=0.8,
        fit_psnr=25.0,
        hdr_unaligned_psnr=10.0,
        ldr_psnr=[(0.01, 20.0), (0.16, 22.0)],
    )
    values.update(kwargs)
    return RunRow("room", "fast", variant, 30.0, hdr_psnr=hdr, **values)


def test_all_orderings_hold():
    rows = {
        "full": row("full", 25.0),
        "deblur-e-lowpass": row("deblur-e-lowpass", 24.0),
        "v2e-lowpass": row("v2e-lowpass", 23.0),
    }
    verdict = judge(TABLE_9_LOWPASS, rows)
    assert [c.outcome for c in verdict.claims] == ["holds"] * 3
    assert verdict.summary == "holds: all 3 orderings as in the paper"


def test_a_reversed_ordering_is_reported_with_measured_differences():
    rows = {
        "full": row("full", 23.5, steps=40, ldr_psnr=[(0.01, 18.5), (0.16, 22.25)]),
        "deblur-e-lowpass": row("deblur-e-lowpass", 24.0),
        "v2e-lowpass": row("v2e-lowpass", 23.0),
    }
    verdict = judge(TABLE_9_LOWPASS, rows)
    reversed_claims = [c for c in verdict.claims if c.outcome == "reversed"]
    assert [(c.claim.better, c.claim.worse) for c in reversed_claims] == [
        ("full", "deblur-e-lowpass")
    ]
    assert verdict.summary == "does not hold: 1 of 3 orderings reversed"
    # full - deblur-e at 0.01 s: 18.5 - 20.0 = -1.50 dB; at 0.16 s: 22.25 - 22.0 = +0.25 dB.
    assert "0.01 s -1.50, 0.16 s +0.25 dB" in reversed_claims[0].reason
    assert "training 40 vs 100 steps" in reversed_claims[0].reason


def test_missing_and_failed_runs_are_not_measured():
    failed = row("v2e-lowpass", math.nan, steps=0)
    failed.status = "failed (exit 1): boom"
    verdict = judge(TABLE_9_LOWPASS, {"full": row("full", 25.0), "v2e-lowpass": failed})
    assert [c.outcome for c in verdict.claims] == ["not measured"] * 3
    assert verdict.summary == "not measured"
    partial = judge(
        TABLE_9_LOWPASS,
        {"full": row("full", 25.0), "deblur-e-lowpass": row("deblur-e-lowpass", 26.0)},
    )
    assert partial.summary == "does not hold: 1 of 1 orderings reversed (2 not measured)"


def test_explain_difference_without_ldr_scores():
    text = explain_difference(row("full", 20.0, ldr_psnr=[]), row("base", 21.0, fit_psnr=24.5))
    assert "LDR" not in text
    assert "fit to the blurry input frames 25.00 vs 24.50 dB" in text


def test_differences_below_the_tie_threshold_decide_nothing():
    # deblur-e 24.00 vs v2e 23.97: 0.03 dB < 0.05 dB is a tie; full 25.0 is above both.
    rows = {
        "full": row("full", 25.0),
        "deblur-e-lowpass": row("deblur-e-lowpass", 24.0),
        "v2e-lowpass": row("v2e-lowpass", 23.97),
    }
    verdict = judge(TABLE_9_LOWPASS, rows)
    assert [c.outcome for c in verdict.claims] == ["tie", "holds", "holds"]
    assert verdict.summary == "undecided: 2 of 3 orderings as in the paper (1 within 0.05 dB)"
    assert "LDR PSNR difference" in verdict.claims[0].reason


def test_explain_difference_leaves_out_unmeasured_components():
    text = explain_difference(
        row("full", 20.0, fit_psnr=math.nan), row("base", 21.0, fit_psnr=math.nan)
    )
    assert "blurry input" not in text


def test_with_seeds_the_means_are_compared_within_twice_their_standard_error():
    rows = {
        "full": row("full", 25.0),
        "deblur-e-lowpass": row("deblur-e-lowpass", 24.0),
        "v2e-lowpass": row("v2e-lowpass", 23.0),
    }
    seeds = {
        "full": [25.0, 25.5, 24.5],  # mean 25.0, variance 0.25, of the mean 0.25 / 3
        "deblur-e-lowpass": [24.0, 25.0, 24.5],  # mean 24.5, same variance
        "v2e-lowpass": [23.0, 23.1, 22.9],  # mean 23.0, variance 0.01
    }
    verdict = judge(TABLE_9_LOWPASS, rows, seeds=seeds)
    claims = {(c.claim.better, c.claim.worse): c for c in verdict.claims}
    # full vs deblur-e: 0.5 dB apart, twice the standard error 2 sqrt(0.5 / 3) = 0.816 dB.
    tie = claims[("full", "deblur-e-lowpass")]
    assert tie.outcome == "tie" and tie.seeds == 3
    assert math.isclose(tie.limit_db, 2 * math.sqrt(0.5 / 3))
    assert (tie.better_db, tie.worse_db) == (25.0, 24.5)
    # deblur-e vs v2e: 1.5 dB apart against 2 sqrt(0.26 / 3) = 0.589 dB.
    assert claims[("deblur-e-lowpass", "v2e-lowpass")].outcome == "holds"
    assert verdict.summary == (
        "undecided: 2 of 3 orderings as in the paper "
        "(1 within twice the standard error of the difference)"
    )
    # A side with a single run falls back to the fixed limit and the default seeds' scores.
    single = judge(TABLE_9_LOWPASS, rows, tie_db=0.05, seeds={**seeds, "v2e-lowpass": [23.0]})
    alone = {(c.claim.better, c.claim.worse): c for c in single.claims}
    assert alone[("full", "v2e-lowpass")].seeds == 1
    assert alone[("full", "v2e-lowpass")].limit_db == 0.05
    assert alone[("full", "v2e-lowpass")].better_db == 25.0
