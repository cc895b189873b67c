from pathlib import Path

from benchlib.fits import fit_command, run_name, rung_row
from benchlib.matching import (
    MATCHED_BUDGET_FACTOR,
    common_steps,
    matched_ladder,
    matched_row,
    needs_matching,
)
from benchlib.plan import Ladder
from benchlib.results import RunRow


def row(variant, steps, hdr=30.0, **kwargs):
    return RunRow("room", "fast", variant, 180.0, hdr_psnr=hdr, steps=steps, **kwargs)


def test_common_steps_are_the_fewest_of_the_scored_rows():
    failed = RunRow("room", "fast", "base", 180.0, steps=10, status="failed (exit 1)")
    assert common_steps([row("full", 1200), None, failed, row("no-events", 3000)]) == 1200
    assert common_steps([None, failed]) == 0


def test_a_row_within_ten_percent_is_matched_already():
    assert not needs_matching(row("no-events", 1320), 1200)  # 1.10 x: within the slack
    assert needs_matching(row("no-events", 1321), 1200)
    assert not needs_matching(None, 1200) and not needs_matching(row("full", 5000), 0)


def test_the_matched_run_ends_at_the_steps_with_room_in_its_budget():
    ladder = matched_ladder(row("base", 3000, seed=2), 1200)
    assert ladder == Ladder("room", "fast", "base", (180.0 * MATCHED_BUDGET_FACTOR,), 2, 1200)
    assert run_name(ladder) == "bench-fast-base-seed2-steps1200"
    command = fit_command(Path("s"), ladder, 360.0, fresh=True)
    assert command[command.index("--steps") + 1] == "1200" and command[-1] == "--fresh"
    assert "--steps" not in fit_command(
        Path("s"), Ladder("room", "fast", "full", (60.0,)), 60, True
    )
    assert rung_row(ladder, 0).step_cap == 1200 and rung_row(ladder, 0).budget_s == 360.0


def test_matched_row_is_the_row_itself_or_its_run_ended_at_the_steps():
    timed, slow = row("base", 3000, hdr=31.0), row("full", 1200)
    capped = row("base", 1200, hdr=28.0, step_cap=1200)
    other = row("base", 900, hdr=27.0, step_cap=900)
    assert matched_row(slow, [timed, other, capped], 1200) is slow
    assert matched_row(timed, [timed, other, capped], 1200) is capped
    assert matched_row(timed, [timed, other], 1200) is None  # not run yet: not measured
