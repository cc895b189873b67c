"""What one benchmark run measures: the sessions, and every preset x variant budget ladder.

The full plan: 236 minutes of training (the table preset's ``full`` up 1, 3 and 10 minutes,
its ten other variants at the 3-minute table budget, its ``oracle`` on to 10 minutes,
``balanced`` ``full`` up the ladder, ``full`` and ``oracle`` for 10 minutes on each of the four
other benchmark scenes, Table 4's five sessions at the table budget, and two more seeds of every
row the paper's comparisons rank) in 58 rungs, each adding about a minute of start-up, rendering
and scoring on an idle machine, plus making the ten sessions and the capture-side tools: about
five hours one rung at a time on a 2-core machine; ``--ray local`` runs two rungs side by side,
one core each (0.65x the wall time on the quick plan, BENCHMARKS.md). The ``paper`` preset is
measured for speed only (:data:`FULL_UNFITTED_PRESETS`).
"""

from __future__ import annotations

from dataclasses import dataclass

from benchlib.paper import COMPARISONS
from seenerf.model.config import DEFAULT_VARIANT

__all__ = [
    "COMPARED_VARIANTS",
    "FULL_BUDGETS_S",
    "METHOD",
    "QUICK_BUDGETS_S",
    "Ladder",
    "Plan",
    "SessionSpec",
    "SCENE_SESSIONS",
    "SEED_REPEATS",
    "TABLE4_ROWS",
    "UPPER_BOUND",
    "make_plan",
    "planned_rungs",
    "planned_training_s",
]

METHOD = DEFAULT_VARIANT
"""The variant the benchmark measures; every other variant is a reference beside it."""

UPPER_BOUND = "oracle"
"""The reference that bounds the method from above (trained on the truth)."""

FULL_BUDGETS_S = (60.0, 180.0, 600.0)
"""Wall-clock budgets of the full benchmark: 1, 3 and 10 minutes (30 would add over an hour per
preset here; pass ``--budgets`` to climb further)."""

FULL_TABLE_BUDGET_S = 180.0
"""Budget at which the full benchmark reads the paper's comparisons: 3 minutes."""

QUICK_BUDGETS_S = (20.0, 60.0)
"""Budgets of ``--quick``: enough to check the whole pipeline and the report, not to converge."""

QUICK_VARIANTS = (
    METHOD,
    "no-events",
    "base",
    "naive-events",
    "point-crf-3d",
    "evdeblur-ecrf",
    "oracle",
)
"""Variants of ``--quick``: Table 3 and the oracle (the trainer's targets need full, base,
no-events and oracle); Table 9's variants run in the full benchmark."""

UNSUPPORTED_VARIANTS = {
    "multi-exposure": "needs frames of several exposures; the benchmark sessions have one",
}
"""Variants left out of the grid, with the reason printed in the report."""

PAPER_PRESET_COST = (
    "one fit of the published batch (1024 pixels x 5 poses x 192 samples through the 8x256 "
    "MLP) held over 13 GB of memory here and renders for minutes"
)
"""What a fit of the ``paper`` preset costs on this kind of machine, printed in the report."""

FULL_UNFITTED_PRESETS = {
    "paper": f"{PAPER_PRESET_COST}: on 2 cores it trained 1 step in 64 s (80 rays/s) and one "
    "346x260 view renders in about 290 s (a tenth of a view timed: 28.7 s), so scoring the 8 "
    "held-out views at each rung would take over an hour; its speed is in the rays-per-second "
    "table",
}
"""Presets the full benchmark measures only for speed, with the reason printed in the report."""

QUICK_UNFITTED_PRESETS = {
    "paper": f"{PAPER_PRESET_COST}; its speed is in the rays-per-second table",
    "balanced": "left out to stay within 15 minutes (each fit costs about a minute beyond its "
    "budget in start-up and renders); its speed is in the rays-per-second table",
}
"""Presets ``--quick`` measures only for speed, with the reason printed in the report."""

REFERENCE_EXPOSURE_US = 16_000
"""Table 4's reference exposure (the paper's 0.016 s); the sweep is x1/16, x1 and x16 of it,
with the sensor gain held at the reference, so shorter exposures are darker, longer ones clip."""


@dataclass(frozen=True)
class SessionSpec:
    """An emulated benchmark session.

    Attributes:
        key: name in the report and folder name.
        scene: built-in emulator scene.
        seed: emulator seed.
        exposure_us: APS exposure, µs.
        gain_exposure_us: exposure whose reciprocal sets the sensor gain (0: ``exposure_us``,
            the emulator's default, which keeps every exposure equally bright).
        noise_scale: multiplier of the DVS leak and shot-noise rates.
        maker: ``benchmark`` (``tools/make_benchmark.py``) or ``bracket`` (this tool's maker).
    """

    key: str
    scene: str = "room"
    seed: int = 1
    exposure_us: int = 150_000
    gain_exposure_us: int = 0
    noise_scale: float = 1.0
    maker: str = "bracket"


@dataclass(frozen=True)
class Ladder:
    """One (session, preset, variant) trained once, scored at each budget on the way.

    ``seed`` is the fit's random seed (0: ``seecap fit``'s default); ``steps`` ends training at
    that many steps (0: the budgets alone end it).
    """

    session: str
    preset: str
    variant: str
    budgets_s: tuple[float, ...]
    seed: int = 0
    steps: int = 0


@dataclass(frozen=True)
class Plan:
    """Everything one invocation measures.

    Attributes:
        quick: the short smoke-test mode.
        views: training and held-out views per session.
        sessions: sessions to make (cached) before fitting.
        ladders: runs, in execution order.
        table_preset: preset of the paper comparisons.
        table_budget_s: budget at which the comparisons are read, s.
        notes: what was left out, and why.
    """

    quick: bool
    views: tuple[int, int]
    sessions: tuple[SessionSpec, ...]
    ladders: tuple[Ladder, ...]
    table_preset: str
    table_budget_s: float
    notes: tuple[str, ...] = ()


MAIN_SESSION = SessionSpec("room", maker="benchmark")

SCENE_SESSIONS = tuple(
    SessionSpec(key, scene=scene, seed=seed, maker="benchmark")
    for key, scene, seed in (
        ("lamp", "lamp", 2),
        ("corridor", "corridor", 3),
        ("room-mono", "room", 4),
        ("lamp-film", "lamp", 5),
    )
)
"""The other ``make_benchmark.py`` scenes (their seeds are that tool's), each fitted with the
table preset's ``full`` and ``oracle`` at the top budget: the trainer's targets per scene."""

SCENE_VARIANTS = (METHOD, UPPER_BOUND)

SEED_REPEATS = (1, 2)
"""Seeds of two more runs of every row of the paper's comparisons at the table budget (each
compared variant on the main session, ``full`` on each Table 4 session): beside the default
seed's run they give each row a mean and a standard error, so an ordering counts only where the
difference of two means exceeds twice its standard error."""

COMPARED_VARIANTS = frozenset(
    key for comparison in COMPARISONS if comparison.axis == "variant" for key in comparison.rows
)
"""Variants some comparison of the paper ranks (their rows get :data:`SEED_REPEATS`)."""

TABLE4_SESSIONS = (
    SessionSpec(
        "t4-exposure-1_16",
        exposure_us=REFERENCE_EXPOSURE_US // 16,
        gain_exposure_us=REFERENCE_EXPOSURE_US,
    ),
    SessionSpec(
        "t4-reference", exposure_us=REFERENCE_EXPOSURE_US, gain_exposure_us=REFERENCE_EXPOSURE_US
    ),
    SessionSpec(
        "t4-exposure-16",
        exposure_us=REFERENCE_EXPOSURE_US * 16,
        gain_exposure_us=REFERENCE_EXPOSURE_US,
    ),
    SessionSpec(
        "t4-noise-2",
        exposure_us=REFERENCE_EXPOSURE_US,
        gain_exposure_us=REFERENCE_EXPOSURE_US,
        noise_scale=2.0,
    ),
    SessionSpec(
        "t4-noise-4",
        exposure_us=REFERENCE_EXPOSURE_US,
        gain_exposure_us=REFERENCE_EXPOSURE_US,
        noise_scale=4.0,
    ),
)

TABLE4_ROWS = {
    "exposure-x1/16": "t4-exposure-1_16",
    "exposure-x1": "t4-reference",
    "exposure-x16": "t4-exposure-16",
    "noise-x1": "t4-reference",
    "noise-x2": "t4-noise-2",
    "noise-x4": "t4-noise-4",
}
"""Table 4 row key -> session fitted for it (the reference session serves both halves)."""


def _grid(
    presets: tuple[str, ...],
    variants: tuple[str, ...],
    budgets: tuple[float, ...],
    table_budget_s: float,
    table_preset: str,
    oracle_at_top: bool,
) -> list[Ladder]:
    """The main session's ladders: ``full`` of every preset climbs every budget (the table
    preset's also stops at the table budget, so the comparisons read every variant at the same
    budget); the table preset's other variants run once, at the table budget; other presets
    run only ``full``; with ``oracle_at_top`` the table preset's ``oracle`` goes on to the top
    budget, to stand beside ``full`` there. The table preset comes first and ``paper`` (the
    slowest) last, so an interrupted run has the comparisons before the costliest rungs."""
    ladders = []
    order = sorted(presets, key=lambda p: (p != table_preset, p == "paper"))
    for preset in order:
        for variant in variants:
            if variant == METHOD:
                rungs = (
                    budgets if preset != table_preset else tuple(sorted({*budgets, table_budget_s}))
                )
                ladders.append(Ladder(MAIN_SESSION.key, preset, variant, rungs))
            elif preset == table_preset:
                rungs = (table_budget_s,)
                if oracle_at_top and variant == UPPER_BOUND and budgets[-1] > table_budget_s:
                    rungs += (budgets[-1],)  # beside full at the top budget
                ladders.append(Ladder(MAIN_SESSION.key, preset, variant, rungs))
    return ladders


def planned_training_s(plan: Plan) -> float:
    """Seconds of training the plan asks for: each ladder's last budget (rungs resume)."""
    return sum(ladder.budgets_s[-1] for ladder in plan.ladders)


def planned_rungs(plan: Plan) -> int:
    """Scored rungs of the plan: one ``seecap fit`` process, render and score each."""
    return sum(len(ladder.budgets_s) for ladder in plan.ladders)


def make_plan(
    quick: bool,
    presets: tuple[str, ...],
    variants: tuple[str, ...],
    budgets_s: tuple[float, ...] = (),
    table_budget_s: float = 0.0,
    table_preset: str = "fast",
    table4: bool | None = None,
    scenes: bool | None = None,
) -> Plan:
    """The plan of one invocation.

    Args:
        quick: short budgets, 4 + 2 views per session, :data:`QUICK_VARIANTS` of the table
            preset, other presets only for ``full`` (none of :data:`QUICK_UNFITTED_PRESETS`).
            Without it, 16 + 8 views; the table preset's ``full`` climbs the ladder and its
            other variants (Tables 3 and 9) run at the table budget; every other preset runs
            only ``full``, up the ladder; each Table 4 session runs ``full`` at the table
            budget; each of :data:`SCENE_SESSIONS` runs :data:`SCENE_VARIANTS` at the top
            budget, and so does the main session's ``oracle``; every row a comparison ranks
            (:data:`COMPARED_VARIANTS` on the main session, ``full`` on each Table 4 session)
            runs again at the table budget with each of :data:`SEED_REPEATS`, last; presets of
            :data:`FULL_UNFITTED_PRESETS` are not fitted. With the defaults that is 236
            minutes of training in 58 rungs.
        presets: every preset to run.
        variants: every variant to run (unsupported ones are left out with a note).
        budgets_s: the budget ladder, s (default: :data:`QUICK_BUDGETS_S` or
            :data:`FULL_BUDGETS_S`).
        table_budget_s: budget of the comparisons (default: the first quick budget, or
            :data:`FULL_TABLE_BUDGET_S`).
        table_preset: preset of the comparisons.
        table4: also make the Table 4 sessions and fit them (None: only without ``quick``).
        scenes: also make :data:`SCENE_SESSIONS` and fit :data:`SCENE_VARIANTS` of the table
            preset on each at the top budget (None: only without ``quick``).
    """
    budgets = tuple(sorted(budgets_s or (QUICK_BUDGETS_S if quick else FULL_BUDGETS_S)))
    table_budget = table_budget_s or (budgets[0] if quick else FULL_TABLE_BUDGET_S)
    notes = [
        f"variant {name} left out: {why}"
        for name, why in UNSUPPORTED_VARIANTS.items()
        if name in variants
    ]
    variants = tuple(v for v in variants if v not in UNSUPPORTED_VARIANTS)
    repeats: list[Ladder] = []
    if quick:
        dropped = [v for v in variants if v not in QUICK_VARIANTS]
        variants = tuple(v for v in variants if v in QUICK_VARIANTS)
        ladders = _grid(
            tuple(p for p in presets if p == table_preset),
            variants,
            budgets,
            table_budget,
            table_preset,
            oracle_at_top=False,
        )
        others = [
            Ladder(MAIN_SESSION.key, p, METHOD, (budgets[0],))
            for p in presets
            if p not in (table_preset, *QUICK_UNFITTED_PRESETS)
        ]
        ladders += others
        if others:
            notes.append("quick mode: other presets run only the full variant at the first budget")
        notes += [
            f"quick mode does not fit the {p} preset: {QUICK_UNFITTED_PRESETS[p]}"
            for p in presets
            if p in QUICK_UNFITTED_PRESETS
        ]
        if dropped:
            notes.append(f"quick mode leaves out {', '.join(dropped)} (run without --quick)")
    else:
        fitted = tuple(p for p in presets if p not in FULL_UNFITTED_PRESETS)
        ladders = _grid(fitted, variants, budgets, table_budget, table_preset, oracle_at_top=True)
        compared = [
            ladder.variant
            for ladder in ladders
            if ladder.preset == table_preset and ladder.variant in COMPARED_VARIANTS
        ]
        repeats = [
            Ladder(MAIN_SESSION.key, table_preset, variant, (table_budget,), seed=seed)
            for seed in SEED_REPEATS
            for variant in compared
        ]
        if any(p != table_preset for p in fitted) and any(v != METHOD for v in variants):
            notes.append(f"presets other than {table_preset} run only the full variant")
        notes += [
            f"the {p} preset is not fitted: {FULL_UNFITTED_PRESETS[p]}"
            for p in presets
            if p in FULL_UNFITTED_PRESETS
        ]
    sessions = [MAIN_SESSION]
    if table4 is None:
        table4 = not quick
    if not table4:
        notes.append("Table 4 sessions not made" + (" in quick mode" if quick else ""))
    else:
        sessions += TABLE4_SESSIONS
        ladders += [Ladder(s.key, table_preset, METHOD, (table_budget,)) for s in TABLE4_SESSIONS]
        if not quick:
            repeats += [
                Ladder(s.key, table_preset, METHOD, (table_budget,), seed=seed)
                for seed in SEED_REPEATS
                for s in TABLE4_SESSIONS
            ]
    if scenes is None:
        scenes = not quick
    if not scenes:
        notes.append("the other benchmark scenes not made" + (" in quick mode" if quick else ""))
    elif table_preset in presets and any(v in variants for v in SCENE_VARIANTS):
        sessions += SCENE_SESSIONS
        ladders += [
            Ladder(spec.key, table_preset, variant, (budgets[-1],))
            for spec in SCENE_SESSIONS
            for variant in SCENE_VARIANTS
            if variant in variants
        ]
    return Plan(
        quick,
        (4, 2) if quick else (16, 8),
        tuple(sessions),
        tuple(ladders + repeats),
        table_preset,
        table_budget,
        tuple(notes),
    )
