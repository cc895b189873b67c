from benchlib.plan import FULL_BUDGETS_S, TABLE4_ROWS, make_plan

PRESETS = ("paper", "fast", "balanced")
VARIANTS = ("full", "no-events", "naive-events", "evdeblur-ecrf", "v2e-lowpass",
            "deblur-e-lowpass", "power-crf", "point-crf-3d", "base", "multi-exposure", "oracle")


def test_quick_plan():
    plan = make_plan(True, PRESETS, VARIANTS)
    assert plan.views == (4, 2) and plan.table_budget_s == 20.0
    assert [s.key for s in plan.sessions] == ["room"]  # no Table 4 sessions unless asked
    # fast: the 7 quick variants, full climbs 20 s and 60 s, the others stop at 20 s;
    # balanced and paper are measured for speed only.
    assert len(plan.ladders) == 7
    assert {(ladder.preset, ladder.budgets_s) for ladder in plan.ladders
            if ladder.variant == "full"} == {("fast", (20.0, 60.0))}
    assert any("does not fit the paper preset" in note for note in plan.notes)
    assert any("does not fit the balanced preset" in note for note in plan.notes)
    assert all(ladder.budgets_s == (20.0,) for ladder in plan.ladders if ladder.variant != "full")
    assert any("multi-exposure" in note for note in plan.notes)
    assert any("v2e-lowpass" in note for note in plan.notes)


def test_quick_plan_with_table4():
    plan = make_plan(True, ("fast",), ("full",), table4=True)
    table4 = [ladder for ladder in plan.ladders if ladder.session != "room"]
    assert {ladder.session for ladder in table4} == set(TABLE4_ROWS.values())
    assert all((ladder.variant, ladder.budgets_s) == ("full", (20.0,)) for ladder in table4)


def test_full_plan_runs_every_preset_and_variant():
    plan = make_plan(False, PRESETS, VARIANTS, table4=False)
    assert "Table 4 sessions not made" in plan.notes
    assert plan.table_budget_s == 600.0 and plan.views == (16, 8)
    assert len(plan.ladders) == 3 * 10
    full = [ladder for ladder in plan.ladders if ladder.variant == "full"]
    assert all(ladder.budgets_s == FULL_BUDGETS_S for ladder in full)
    others = [ladder for ladder in plan.ladders if ladder.variant != "full"]
    assert all(ladder.budgets_s == (60.0, 180.0, 600.0) for ladder in others)
    assert [s.key for s in plan.sessions] == ["room"]


def test_budgets_below_the_table_budget_keep_the_first():
    plan = make_plan(False, ("fast",), ("full", "base"), budgets_s=(900.0, 1200.0),
                     table_budget_s=600.0, table4=False)
    assert [(ladder.variant, ladder.budgets_s) for ladder in plan.ladders] == [
        ("full", (900.0, 1200.0)), ("base", (900.0,))]


def test_quick_plan_honours_the_preset_list():
    plan = make_plan(True, ("fast",), ("full", "base", "power-crf"))
    assert [(ladder.preset, ladder.variant) for ladder in plan.ladders] == [
        ("fast", "full"), ("fast", "base")]
    assert "quick mode leaves out power-crf (run without --quick)" in plan.notes
