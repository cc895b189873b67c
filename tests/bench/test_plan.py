from benchlib.plan import (
    SCENE_SESSIONS,
    TABLE4_ROWS,
    make_plan,
    planned_rungs,
    planned_training_s,
)

PRESETS = ("paper", "fast", "balanced")
VARIANTS = (
    "full",
    "no-events",
    "naive-events",
    "evdeblur-ecrf",
    "v2e-lowpass",
    "deblur-e-lowpass",
    "power-crf",
    "point-crf-3d",
    "base",
    "multi-exposure",
    "oracle",
)


def test_quick_plan():
    plan = make_plan(True, PRESETS, VARIANTS)
    assert plan.views == (4, 2) and plan.table_budget_s == 20.0
    assert [s.key for s in plan.sessions] == ["room"]  # no Table 4 sessions unless asked
    # fast: the 7 quick variants, full climbs 20 s and 60 s, the others stop at 20 s;
    # balanced and paper are measured for speed only.
    assert len(plan.ladders) == 7
    assert {
        (ladder.preset, ladder.budgets_s) for ladder in plan.ladders if ladder.variant == "full"
    } == {("fast", (20.0, 60.0))}
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


def test_full_plan_ladders_and_totals():
    plan = make_plan(False, PRESETS, VARIANTS)
    assert plan.table_budget_s == 180.0 and plan.views == (16, 8)
    # Two more seeds of every row the paper's comparisons rank, at the table budget, last:
    # the nine compared variants on the main session, then full on the five Table 4 sessions.
    repeats = [ladder for ladder in plan.ladders if ladder.seed]
    assert plan.ladders[-len(repeats) :] == tuple(repeats) and len(repeats) == 2 * (9 + 5)
    assert {(r.preset, r.budgets_s) for r in repeats} == {("fast", (180.0,))}
    compared = {r.variant for r in repeats if r.session == "room"}
    assert compared == set(VARIANTS) - {"multi-exposure", "oracle"}
    assert {r.session for r in repeats if r.session != "room"} == set(TABLE4_ROWS.values())
    assert [r.seed for r in repeats] == [1] * 9 + [2] * 9 + [1] * 5 + [2] * 5
    by_run = {
        (ladder.session, ladder.preset, ladder.variant): ladder.budgets_s
        for ladder in plan.ladders
        if not ladder.seed
    }
    ladder = (60.0, 180.0, 600.0)
    # Every fitted preset's full variant climbs 1, 3 and 10 minutes; paper is timed only.
    for preset in ("fast", "balanced"):
        assert by_run.pop(("room", preset, "full")) == ladder
    assert not any(key[1] == "paper" for key in by_run)
    # The oracle is read at the table budget and again beside full at 10 minutes.
    assert by_run.pop(("room", "fast", "oracle")) == (180.0, 600.0)
    # The fast preset's 8 other supported variants run once at the 3-minute table budget.
    others = {key: budgets for key, budgets in by_run.items() if key[0] == "room"}
    assert set(others) == {
        ("room", "fast", v) for v in VARIANTS if v not in ("full", "multi-exposure", "oracle")
    }
    assert set(others.values()) == {(180.0,)}
    # Table 4: five sessions, the fast preset's full variant at the table budget.
    table4 = {key: budgets for key, budgets in by_run.items() if key[0] in TABLE4_ROWS.values()}
    assert {key[0] for key in table4} == set(TABLE4_ROWS.values())
    assert {key[1:] for key in table4} == {("fast", "full")}
    assert set(table4.values()) == {(180.0,)}
    # The four other scenes: full and oracle for 10 minutes each.
    scenes = {key: budgets for key, budgets in by_run.items() if key not in others | table4}
    assert set(scenes) == {
        (spec.key, "fast", v) for spec in SCENE_SESSIONS for v in ("full", "oracle")
    }
    assert set(scenes.values()) == {(600.0,)}
    assert [s.key for s in plan.sessions[-4:]] == ["lamp", "corridor", "room-mono", "lamp-film"]
    assert len(plan.sessions) == 10
    # 2 x 10 min + 9 x 3 min + 7 min (oracle on) + 5 x 3 min + 8 x 10 min + seeds 28 x 3 min
    # = 233 min in 2 x 3 + 9 + 1 + 5 + 8 + 28 = 57 rungs.
    assert planned_training_s(plan) == 233 * 60.0
    assert planned_rungs(plan) == 57
    assert "presets other than fast run only the full variant" in plan.notes
    assert any(note.startswith("the paper preset is not fitted: one fit") for note in plan.notes)


def test_full_plan_without_table4_or_scenes():
    plan = make_plan(False, PRESETS, VARIANTS, table4=False, scenes=False)
    assert "Table 4 sessions not made" in plan.notes
    assert "the other benchmark scenes not made" in plan.notes
    assert [s.key for s in plan.sessions] == ["room"]
    # 2 x 10 + 9 x 3 + 7 min, then 9 compared variants x 2 seeds x 3 min, in 16 + 18 rungs.
    assert planned_training_s(plan) == (20 + 27 + 7 + 54) * 60.0 and planned_rungs(plan) == 34


def test_quick_plan_totals():
    plan = make_plan(True, PRESETS, VARIANTS)
    # fast/full up 20 s and 60 s, six other variants at 20 s.
    assert planned_training_s(plan) == 60.0 + 6 * 20.0
    assert planned_rungs(plan) == 2 + 6


def test_overridden_budgets_put_the_table_budget_on_the_table_presets_ladder():
    plan = make_plan(
        False,
        ("fast", "balanced"),
        ("full", "base"),
        budgets_s=(900.0, 1200.0),
        table_budget_s=600.0,
        table4=False,
        scenes=False,
    )
    assert [
        (ladder.preset, ladder.variant, ladder.budgets_s, ladder.seed) for ladder in plan.ladders
    ] == [
        ("fast", "full", (600.0, 900.0, 1200.0), 0),
        ("fast", "base", (600.0,), 0),
        ("balanced", "full", (900.0, 1200.0), 0),
        ("fast", "full", (600.0,), 1),
        ("fast", "base", (600.0,), 1),
        ("fast", "full", (600.0,), 2),
        ("fast", "base", (600.0,), 2),
    ]


def test_quick_plan_honours_the_preset_list():
    plan = make_plan(True, ("fast",), ("full", "base", "power-crf"))
    assert [(ladder.preset, ladder.variant) for ladder in plan.ladders] == [
        ("fast", "full"),
        ("fast", "base"),
    ]
    assert "quick mode leaves out power-crf (run without --quick)" in plan.notes
