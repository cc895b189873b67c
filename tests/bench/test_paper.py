from benchlib.paper import COMPARISONS, TABLE_3, TABLE_4_NOISE, TABLE_9_LOWPASS, paper_claims


def pairs(claims):
    return {(c.better, c.worse, c.column) for c in claims}


def test_lowpass_claims_follow_the_real_hdr_column():
    # Real HDR column: full 26.49 > Deblur-e 24.28 > v2e 22.10, so three strict orderings.
    assert pairs(paper_claims(TABLE_9_LOWPASS)) == {
        ("deblur-e-lowpass", "v2e-lowpass", "real HDR"),
        ("full", "v2e-lowpass", "real HDR"),
        ("full", "deblur-e-lowpass", "real HDR"),
    }


def test_table3_base_is_ranked_on_the_only_column_that_reports_it():
    claims = paper_claims(TABLE_3)
    # 5 rows share the synthetic column: C(5, 2) = 10 pairs, all with distinct PSNR; base is
    # reported only on Real-World-Challenge (28.79), below every other row there: 5 more.
    assert len(claims) == 15
    base = [c for c in claims if "base" in (c.better, c.worse)]
    assert {c.column for c in base} == {"Real-World-Challenge"}
    assert all(c.worse == "base" for c in base)
    no_events_over_3d = [c for c in claims if (c.better, c.worse) == ("no-events", "point-crf-3d")]
    assert [(c.better_db, c.worse_db) for c in no_events_over_3d] == [(22.19, 20.67)]


def test_noise_claims_are_monotone_and_ties_make_none():
    assert pairs(paper_claims(TABLE_4_NOISE)) == {
        ("noise-x1", "noise-x2", "synthetic HDR (Catroom)"),
        ("noise-x1", "noise-x4", "synthetic HDR (Catroom)"),
        ("noise-x2", "noise-x4", "synthetic HDR (Catroom)"),
    }


def test_every_row_has_one_value_per_column():
    for comparison in COMPARISONS:
        for label, values in comparison.rows.values():
            assert len(values) == len(comparison.columns), (comparison.key, label)
