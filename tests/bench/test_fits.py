import json
from pathlib import Path

import pytest
from benchlib import fits
from benchlib.fits import KEPT_KEY, kept_path, reusable_rungs, run_ladder
from benchlib.plan import Ladder
from benchlib.results import ProcessUsage

LADDER = Ladder("room", "fast", "full", (60.0, 180.0, 600.0))
USAGE = {"returncode": 0, "wall_s": 70.0, "cpu_s": 130.0, "peak_rss_mb": 900.0, "timed_out": False}


def metrics(budget_s, psnr, stopped="budget"):
    return {
        "hdr": {"psnr": psnr, "ssim": 0.9},
        "training": {"steps": int(budget_s), "elapsed_s": budget_s, "stopped": stopped},
    }


def keep(out, session, budget_s, psnr, made_on=None):
    path = kept_path(out, LADDER, budget_s)
    path.parent.mkdir(parents=True, exist_ok=True)
    made = {"session_dir": str(made_on or session), "process": USAGE}
    path.write_text(json.dumps({**metrics(budget_s, psnr), KEPT_KEY: made}))


def checkpoint(session):
    run = session / "fit" / "bench-fast-full"
    run.mkdir(parents=True, exist_ok=True)
    (run / "checkpoint.pt").write_bytes(b"")


def test_kept_path_layout(tmp_path):
    assert kept_path(tmp_path, LADDER, 180.0) == tmp_path / "runs/room/bench-fast-full/180s.json"


def test_reuse_needs_the_checkpoint_and_a_leading_run_of_kept_rungs(tmp_path):
    out, session = tmp_path / "out", tmp_path / "sessions/full-truth/room"
    keep(out, session, 60.0, 20.0)
    keep(out, session, 180.0, 22.0)
    assert reusable_rungs(LADDER, session, out) == []  # no checkpoint to resume from
    checkpoint(session)
    kept = reusable_rungs(LADDER, session, out)
    assert [m["hdr"]["psnr"] for m in kept] == [20.0, 22.0]
    kept_path(out, LADDER, 60.0).unlink()
    assert reusable_rungs(LADDER, session, out) == []  # 180 s alone comes after a rung to train


def test_rungs_kept_for_another_session_folder_or_unreadable_are_not_reused(tmp_path):
    out, session = tmp_path / "out", tmp_path / "sessions/full-truth/room"
    checkpoint(session)
    keep(out, session, 60.0, 20.0, made_on=tmp_path / "sessions/quick-truth/room")
    assert reusable_rungs(LADDER, session, out) == []
    kept_path(out, LADDER, 60.0).write_text("{trunc")
    assert reusable_rungs(LADDER, session, out) == []


@pytest.fixture
def fake_fit(monkeypatch):
    """``run_measured`` standing in for ``seecap fit``: records each call, writes its metrics."""
    calls = []

    def run_measured(argv, log, *, timeout_s):
        budget = float(argv[argv.index("--time-budget") + 1].rstrip("s"))
        session = Path(argv[argv.index("fit") + 1])
        calls.append((budget, "--fresh" in argv))
        checkpoint(session)
        (session / "fit" / "bench-fast-full" / "metrics.json").write_text(
            json.dumps(metrics(budget, 30.0 + budget / 60))
        )
        return ProcessUsage(0, budget + 5, budget, 500.0)

    monkeypatch.setattr(fits, "run_measured", run_measured)
    return calls


def test_a_rerun_trains_only_the_remaining_rungs(tmp_path, fake_fit):
    out, session = tmp_path / "out", tmp_path / "sessions/full-truth/room"
    checkpoint(session)
    keep(out, session, 60.0, 20.0)
    rows = run_ladder(LADDER, session, out, progress=lambda line: None)
    assert fake_fit == [(180.0, False), (600.0, False)]  # resumed, not fresh
    assert [(r.budget_s, r.reused, r.hdr_psnr) for r in rows] == [
        (60.0, True, 20.0),
        (180.0, False, 33.0),
        (600.0, False, 40.0),
    ]
    assert rows[0].process == ProcessUsage(0, 70.0, 130.0, 900.0)
    assert rows[1].process.wall_s == 185.0
    kept = json.loads(kept_path(out, LADDER, 600.0).read_text())
    assert kept["hdr"]["psnr"] == 40.0 and kept[KEPT_KEY]["session_dir"] == str(session)
    # A second rerun reads every rung back and trains nothing.
    again = run_ladder(LADDER, session, out, progress=lambda line: None)
    assert len(fake_fit) == 2 and all(r.reused and r.ok for r in again)
    assert [r.hdr_psnr for r in again] == [20.0, 33.0, 40.0]


def test_fresh_trains_every_rung_from_scratch(tmp_path, fake_fit):
    out, session = tmp_path / "out", tmp_path / "sessions/full-truth/room"
    checkpoint(session)
    for budget in LADDER.budgets_s:
        keep(out, session, budget, 20.0)
    rows = run_ladder(LADDER, session, out, fresh=True, progress=lambda line: None)
    assert fake_fit == [(60.0, True), (180.0, False), (600.0, False)]
    assert not any(r.reused for r in rows)


def test_a_kept_rung_that_stopped_early_ends_the_ladder(tmp_path, fake_fit):
    out, session = tmp_path / "out", tmp_path / "sessions/full-truth/room"
    checkpoint(session)
    path = kept_path(out, LADDER, 60.0)
    path.parent.mkdir(parents=True)
    made = {"session_dir": str(session), "process": USAGE}
    path.write_text(json.dumps({**metrics(60.0, 20.0, stopped="plateau"), KEPT_KEY: made}))
    rows = run_ladder(LADDER, session, out, progress=lambda line: None)
    assert fake_fit == [] and [(r.budget_s, r.stopped) for r in rows] == [(60.0, "plateau")]


def test_a_larger_rung_kept_by_another_ladder_means_starting_over(tmp_path, fake_fit):
    out, session = tmp_path / "out", tmp_path / "sessions/full-truth/room"
    checkpoint(session)
    keep(out, session, 60.0, 20.0)
    keep(out, session, 180.0, 22.0)
    keep(out, session, 1800.0, 35.0)  # an older 30-minute ladder: the checkpoint is past 600 s
    assert reusable_rungs(LADDER, session, out) == []
    run_ladder(LADDER, session, out, progress=lambda line: None)
    assert fake_fit == [(60.0, True), (180.0, False), (600.0, False)]
    assert sorted(p.name for p in kept_path(out, LADDER, 60.0).parent.iterdir()) == [
        "180s.json",
        "600s.json",
        "60s.json",
    ]
