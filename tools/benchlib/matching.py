"""The paper's comparisons matched on training steps as well as on wall time.

At one time budget a faster variant trains more steps, so an ordering read at equal time can
say "faster" where the paper says "better". Each comparison is therefore read a second way:
every row at the fewest steps any of its rows trained within the budget. A row within
:data:`STEPS_SLACK` of that count is its time-matched run; a row past it is trained again with
that step count as its end (``seecap fit --steps``), its learning rate falling over those steps
as the slowest row's fell over its budget.
"""

from __future__ import annotations

from collections.abc import Iterable

from benchlib.plan import Ladder
from benchlib.results import RunRow

__all__ = [
    "MATCHED_BUDGET_FACTOR",
    "STEPS_SLACK",
    "common_steps",
    "matched_ladder",
    "matched_row",
    "needs_matching",
]

STEPS_SLACK = 1.1
"""Rows whose steps are within this factor of the comparison's fewest count as matched."""

MATCHED_BUDGET_FACTOR = 2.0
"""Time budget of a step-matched run over the table budget: it reaches its steps sooner than
the slowest row did (it is faster), so the budget only guards against a stalled machine."""


def common_steps(rows: Iterable[RunRow | None]) -> int:
    """The fewest steps any scored row trained (0 when none was scored)."""
    return min((row.steps for row in rows if row is not None and row.ok), default=0)


def needs_matching(row: RunRow | None, steps: int) -> bool:
    """Whether ``row`` trained past ``steps`` by more than :data:`STEPS_SLACK`."""
    return row is not None and row.ok and steps > 0 and row.steps > STEPS_SLACK * steps


def matched_ladder(row: RunRow, steps: int) -> Ladder:
    """The run of ``row``'s session, preset, variant and seed that ends at ``steps``."""
    budget = row.budget_s * MATCHED_BUDGET_FACTOR
    return Ladder(row.session, row.preset, row.variant, (budget,), row.seed, steps=steps)


def matched_row(row: RunRow | None, rows: list[RunRow], steps: int) -> RunRow | None:
    """``row`` itself when it is within the slack of ``steps``, else its run that ended at
    ``steps`` (None when that has not run)."""
    if row is None or not needs_matching(row, steps):
        return row
    return next(
        (
            r
            for r in rows
            if r.step_cap == steps
            and (r.session, r.preset, r.variant, r.seed)
            == (row.session, row.preset, row.variant, row.seed)
        ),
        None,
    )
