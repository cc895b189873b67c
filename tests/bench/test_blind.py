import json
import math
from pathlib import Path

import pytest
from benchlib.blind import BLIND_SESSIONS, BlindRow, blind_rows_markdown, blind_targets

ROOT = Path(__file__).resolve().parents[2]

SENSOR = {
    "color_filter": "mono",
    "dvs": {
        "threshold_on": 0.30,
        "threshold_off": 0.40,
        "threshold_sigma": 0.03,
        "cutoff_hz": 4000.0,
        "refractory_us": 0,
    },
    "response": {"family": "linear"},
    "event_delay_us": 1500,
}


BRACKET = {"0.009375": 31.0, "0.0375": 30.0, "0.15": 29.0, "0.6": 26.0, "2.4": 24.0}


def scores(hdr, novel, contrast=1.0):
    return {
        "hdr": hdr,
        "novel": novel,
        "log_contrast": contrast,
        "registered_hdr": math.nan,
        "ldr": BRACKET,
    }


def test_targets_of_a_session_that_meets_them_and_of_one_that_misses():
    row = BlindRow(
        "room-s1",
        sensor=SENSOR,
        calibration={
            "threshold_on": 0.32,
            "threshold_off": 0.37,
            "threshold_on_sd": 0.011,  # 0.02 off: within 2 sigma
            "threshold_off_sd": 0.02,  # 0.03 off: within 2 sigma
            "latency_us": 1400,
        },
        scores={
            "full": scores(30.0, 28.0, 0.95),
            "white-box": scores(30.8, 28.9),  # 0.8 and 0.9 dB better: within 1 dB
            "oracle": scores(32.9, 31.0),  # 2.9 and 3.0 dB: within 3 dB
        },
        poses={"rotation_median_deg": 0.31, "rotation_max_deg": 0.9, "registered": 1.0},
    )
    on, off = row.threshold_errors()
    assert math.isclose(on, 0.32 / 0.30 - 1) and math.isclose(off, 0.37 / 0.40 - 1)
    assert row.clean_pixel
    assert all(blind_targets(row).values())
    row.scores["full"] = scores(29.5, 28.0, 0.75)
    row.calibration["threshold_off"] = 0.35  # 12.5 % low, 2.5 sigma
    row.calibration["latency_us"] = 12_000  # the profile's last value
    row.poses["rotation_median_deg"] = 0.6
    missed = [name for name, met in blind_targets(row).items() if met is False]
    assert missed == [
        "log contrast 0.8-1.2",
        "white-box − full ≤ 1 dB (hdr)",
        "oracle − full ≤ 3 dB (hdr)",
        "poses ≤ 0.5° median",
        "no stored value at a search bound",
        "truth within 2 stated σ",
        "thresholds within 10 % (clean pixels, measured)",
    ]


def test_a_lagging_pixel_is_not_held_to_the_threshold_target_and_missing_runs_are_unmeasured():
    lagging = {**SENSOR, "dvs": {**SENSOR["dvs"], "refractory_us": 500}}
    row = BlindRow("lamp-s2", sensor=lagging, scores={"full": scores(30.0, 28.0)})
    targets = blind_targets(row)
    assert targets["thresholds within 10 % (clean pixels, measured)"] is None
    assert targets["white-box − full ≤ 1 dB (hdr)"] is None and targets["log contrast 0.8-1.2"]
    assert targets["poses ≤ 0.5° median"] is None and targets["truth within 2 stated σ"] is None
    table = blind_rows_markdown([row])
    assert "lamp-s2" in table and "30.00" in table and "mono, linear" in table
    # The bracket is listed shortest exposure first, whatever the order of the keys.
    assert "| lamp-s2 | full | 31.00 | 30.00 | 29.00 | 26.00 | 24.00 |" in table
    # The events' share of the contrast is not measured for this row; with it, both readings.
    assert "| lamp-s2 | default | mono, linear" in table and "| - |" in table
    row.event_contrast = {"measured": 0.634, "true": 0.886}
    assert "| 0.63 / 0.89 |" in blind_rows_markdown([row])


def test_assumed_thresholds_are_not_scored_as_measured_ones():
    nominal = {"threshold_on": 0.3, "threshold_off": 0.3, "threshold_on_sd": 0.15, "latency_us": 0}
    row = BlindRow("room-s3", sensor=SENSOR, calibration={**nominal, "threshold_off_sd": 0.15})
    label = "thresholds within 10 % (clean pixels, measured)"
    assert blind_targets(row)[label] is False  # OFF 25 % below the drawn 0.40
    row.calibration["assumed"] = {"thresholds": "the search ended at its bound"}
    assert blind_targets(row)[label] is None
    assert blind_targets(row)["truth within 2 stated σ"]


def test_the_plan_has_ten_sessions_four_recorded_as_users_do():
    from davis_io.emulator import draw_sensor
    from davis_io.types import ColorFilter

    assert len(BLIND_SESSIONS) >= 10
    other = [spec for spec in BLIND_SESSIONS if spec.describe()]
    assert len(other) >= 4
    assert any(spec.event_window_ms for spec in other)  # events only around exposures
    assert any(0.02 <= spec.exposure_s <= 0.05 and spec.frame_interval_s == 0.2 for spec in other)
    assert any(draw_sensor(spec.seed).color_filter is not ColorFilter.MONO for spec in other)
    assert BLIND_SESSIONS[6].record_options() == [
        "--exposure",
        "0.05",
        "--frame-interval",
        "0.2",
        "--event-window",
        "3ms",
    ]
    lensed = [spec for spec in BLIND_SESSIONS if spec.lens != "pinhole"]
    assert lensed and lensed[0].record_options()[-2:] == ["--lens", "random"]
    assert "distorted lens" in lensed[0].describe()
    automatic = [spec for spec in BLIND_SESSIONS if spec.auto_exposure]
    assert automatic[0].record_options()[-2:] == ["--auto-exposure", "1,0.5,0.25"]
    assert "auto exposure of 150/75/37.5 ms in turn" in automatic[0].describe()
    small = [spec for spec in BLIND_SESSIONS if spec.camera == "DAVIS240"]
    assert small[0].record_options()[-2:] == ["--camera", "DAVIS240"]
    assert small[0].describe() == "a DAVIS240"
    assert {spec.scene for spec in BLIND_SESSIONS} == {"room", "lamp", "corridor"}
    assert len({spec.key for spec in BLIND_SESSIONS}) == len(BLIND_SESSIONS)
    sensors = [draw_sensor(spec.seed) for spec in BLIND_SESSIONS]
    assert sum(s.color_filter is ColorFilter.MONO for s in sensors) >= 2
    clean = [s.dvs.refractory_us == 0 and s.dvs.cutoff_hz > 1000 for s in sensors]
    assert sum(clean) >= 2  # where the threshold target applies
    assert {s.response.family for s in sensors} == {"linear", "reinhard_gamma", "film", "s_curve"}


def one_run(commit: str) -> dict:
    """The published sessions as one run's ``blind.json`` at ``commit``."""
    published = json.loads((ROOT / "bench-results" / "blind.json").read_text())
    published.pop("runs", None)
    return {
        **published,
        "commit": commit,
        "command": "python tools/bench_blind.py",
        "machine": "a test machine",
        "wall_s": 3600.0,
    }


def test_render_only_reports_the_runs_own_header_and_fits_nothing(tmp_path, capsys):
    import bench_blind  # tools/, on the path by conftest

    document = one_run("0123abcd")  # not this checkout's commit: the run's own must be kept
    (tmp_path / "blind.json").write_text(json.dumps(document))
    assert bench_blind.main(["--out", str(tmp_path), "--render-only"]) == 0
    assert "At commit `0123abcd`" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blind.json"]


def test_runs_merged_keep_each_sessions_own_run_and_refuse_other_budgets(tmp_path, capsys):
    import bench_blind
    from benchlib.blind import merged_runs

    published = one_run("aaaa")
    rows = {row["key"]: row for row in published["rows"]}
    first = {**published, "rows": [rows["lamp-s5"], rows["room-s10"]]}
    # The second run fitted room-s10 again: its row replaces the first run's.
    again = {**rows["room-s10"], "end_to_end_s": 1.0}
    second = {**one_run("bbbb"), "wall_s": 7200.0, "rows": [again]}
    for name, document in (("first", first), ("second", second)):
        (tmp_path / name).mkdir()
        (tmp_path / name / "blind.json").write_text(json.dumps(document))
    merged = merged_runs([first, second])
    assert [row["key"] for row in merged["rows"]] == ["room-s10", "lamp-s5"]  # the plan's order
    assert merged["rows"][0]["end_to_end_s"] == 1.0
    assert [(run["commit"], run["sessions"]) for run in merged["runs"]] == [
        ("aaaa", ["lamp-s5"]),
        ("bbbb", ["room-s10"]),
    ]
    folders = [str(tmp_path / "first"), str(tmp_path / "second")]
    assert bench_blind.main(["--out", str(tmp_path / "out"), "--merge", *folders]) == 0
    out = capsys.readouterr().out
    assert "In 2 runs, each session from one:" in out
    assert "* `lamp-s5`: at commit `aaaa`" in out and "* `room-s10`: at commit `bbbb`" in out
    assert "; 2.0 h." in out
    with pytest.raises(ValueError, match="budget_s"):
        merged_runs([first, {**second, "budget_s": 180.0}])


def test_a_part_run_again_merges_into_the_published_merge():
    from benchlib.blind import merged_runs

    published = one_run("aaaa")
    rows = {row["key"]: row for row in published["rows"]}
    first = {**published, "rows": [rows["lamp-s5"], rows["room-s10"]]}
    second = {**one_run("bbbb"), "wall_s": 7200.0, "rows": [rows["room-s10"]]}
    merged = merged_runs([first, second])  # as published: lamp-s5 from aaaa, room-s10 from bbbb
    third = {**one_run("cccc"), "rows": [{**rows["lamp-s5"], "end_to_end_s": 2.0}]}
    again = merged_runs([merged, third])
    # aaaa has no session left and is dropped; bbbb keeps its facts and its session.
    assert [(run["commit"], run["sessions"]) for run in again["runs"]] == [
        ("bbbb", ["room-s10"]),
        ("cccc", ["lamp-s5"]),
    ]
    assert again["runs"][0]["wall_s"] == 7200.0
    assert [row["end_to_end_s"] for row in again["rows"]] == [
        rows["room-s10"]["end_to_end_s"],
        2.0,
    ]
