from benchlib import cluster
from benchlib.plan import Ladder
from benchlib.results import RunRow

LADDER = Ladder("room", "fast", "full", (20.0, 60.0))


def scored(budget, stopped="budget", status="ok"):
    return RunRow("room", "fast", "full", budget, status=status, stopped=stopped, hdr_psnr=25.0)


def test_a_rung_task_trains_only_while_its_ladder_goes_on(monkeypatch, tmp_path):
    trained = []
    monkeypatch.setattr(
        cluster, "train_rung", lambda ladder, index, *a, **k: trained.append(index) or scored(60)
    )
    assert cluster._rung_task(None, LADDER, 0, tmp_path, tmp_path, True).budget_s == 60
    assert cluster._rung_task(scored(20), LADDER, 1, tmp_path, tmp_path, False) is not None
    assert (
        cluster._rung_task(scored(20, stopped="plateau"), LADDER, 1, tmp_path, tmp_path, False)
        is None
    )
    assert (
        cluster._rung_task(scored(20, status="failed"), LADDER, 1, tmp_path, tmp_path, False)
        is None
    )
    assert trained == [0, 1]


def test_a_chain_keeps_its_rows_up_to_where_the_ladder_ended():
    ok, failed = scored(20), scored(60, status="failed (exit 1): x")
    assert cluster._up_to_the_end([ok, failed, scored(180)]) == [ok, failed]
    assert cluster._up_to_the_end([ok, None, None]) == [ok]
    assert cluster._up_to_the_end([]) == []
