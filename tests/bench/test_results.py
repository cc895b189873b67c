import math

from benchlib.results import RunRow, row_from_metrics

METRICS = {
    "render_s_per_view": 0.8,
    "hdr": {"psnr": 24.5, "ssim": 0.9},
    "hdr_unaligned": {"psnr": 11.0, "ssim": 0.5},
    "novel_exposure": {"psnr": 27.0, "ssim": 0.93},
    "ldr": {"0.16": {"psnr": 28.0, "ssim": 0.9}, "0.01": {"psnr": 26.0, "ssim": 0.9}},
    "training": {
        "steps": 120,
        "elapsed_s": 60.5,
        "stopped": "budget",
        "rays_per_s": 5000.0,
        "best_validation_psnr": None,
        "history": [{"step": 100, "ldr": 0.01, "events": 2.5, "val_psnr": 20.0}],
    },
}


def test_row_from_metrics_reads_scores_and_training():
    row = row_from_metrics(RunRow("room", "fast", "full", 60.0), METRICS)
    assert row.ok
    assert (row.hdr_psnr, row.novel_ssim, row.steps, row.train_s) == (24.5, 0.93, 120, 60.5)
    assert row.ldr_psnr == [(0.01, 26.0), (0.16, 28.0)]  # sorted by exposure
    assert math.isnan(row.fit_psnr)  # JSON null: no evaluation happened inside the budget
    assert row.last_terms == {"ldr": 0.01, "events": 2.5}


def test_metrics_without_truth_are_not_ok():
    row = row_from_metrics(RunRow("real", "fast", "full", 60.0), {"training": {}})
    assert not row.ok
    assert row.status == "no ground truth in metrics.json"
    assert row.steps == 0 and row.ldr_psnr == []


def test_row_reads_the_registered_extra_scores_and_the_crf_error():
    metrics = {
        **METRICS,
        "test_poses": {
            "registered": True,
            "turned_deg": [0.25, 1.5],
            "registered_scores": {"hdr_psnr": 22.5, "novel_exposure_psnr": 20.25},
        },
        "crf_error": {"rms": [0.01, None, 0.03], "max": [0.1, None, 0.2]},
    }
    row = row_from_metrics(RunRow("room", "fast", "full", 600.0), metrics)
    assert (row.registered_hdr_psnr, row.registered_novel_psnr) == (22.5, 20.25)
    assert row.test_pose_turn_deg == [0.25, 1.5]
    assert row.crf_rms == 0.03  # the worst channel; a channel with no comparison is left out
    plain = row_from_metrics(RunRow("room", "fast", "oracle", 600.0), METRICS)
    assert math.isnan(plain.registered_hdr_psnr) and math.isnan(plain.crf_rms)
    assert plain.test_pose_turn_deg == []
