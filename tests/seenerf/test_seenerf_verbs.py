import argparse
import json
import subprocess
import sys

import pytest
import torch

from davis_io.cli import VERBS
from davis_io.session import seconds_argument
from seenerf.cli import fit_verb
from seenerf.eval.scores import format_scores
from seenerf.model.config import FitConfig
from seenerf.train import fit_data


def test_budget_parsing():
    budget = seconds_argument("--time-budget")
    assert budget("10m") == 600
    assert budget("1.5h") == 5400
    assert budget("90") == 90
    assert budget("250ms") == pytest.approx(0.25)
    with pytest.raises(argparse.ArgumentTypeError, match="'soon' is not a duration"):
        budget("soon")
    with pytest.raises(argparse.ArgumentTypeError, match="must be > 0"):
        budget("-1")


def test_verbs_are_registered_and_import_without_torch():
    assert VERBS["fit"] == "seenerf.cli.fit_verb"
    code = (
        "import sys, seenerf, seenerf.cli.fit_verb, seenerf.cli.render_verb, "
        "seenerf.cli.eval_verb; print('torch' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_fit_writes_every_output(tiny_scene, tmp_path):
    config = FitConfig.of(steps=3, batch_pixels=8, warm_steps=2, validation_share=0.1)
    result = fit_data(tiny_scene, config, tmp_path / "run", log=lambda line: None)
    run = result.run_dir
    exposures = [f"{e:g}" for e in tiny_scene.test.exposures_s]
    assert (run / "renders" / "hdr" / "000.exr").exists()
    assert (run / "renders" / "hdr" / "000.png").exists()
    assert all((run / "renders" / "ldr" / e / "000.png").exists() for e in exposures)
    assert (run / "crf.png").exists() and (run / "checkpoint.pt").exists()
    saved = json.loads((run / "config.json").read_text())
    assert saved["config"]["schedule"]["steps"] == 3 and saved["field"] == "vector-matrix"
    metrics = json.loads((run / "metrics.json").read_text())
    assert metrics["training"]["steps"] == 3
    assert set(metrics["ldr"]) == set(exposures)
    transforms = json.loads((run / "transforms.json").read_text())
    assert len(transforms["frames"]) == len(tiny_scene.test.c2w)
    assert 0.0 <= metrics["residual_blur"]["sigma_px"] <= 2.0
    assert "novel exposures" in format_scores(metrics) and "sharpness" in format_scores(metrics)
    # One exposure rendered: no novel ones to score, and the printout says so.
    metrics["novel_exposure"] = {"psnr": None, "ssim": None}
    assert "novel exposures (2nd, 4th):       not scored" in format_scores(metrics)


def test_fit_verb_prepares_the_session_then_passes_the_contrast_threshold(monkeypatch, tmp_path):
    import seenerf.cli.sessions

    seen = {}

    def fake_prepare(session, b, log=print, camera_calibration=None, threads=0):
        seen["prepared"] = (session, b)
        return 12.5

    def fake_fit_session(session, config, run_name=None, fresh=False, spent_s=0.0, **progress):
        seen["config"], seen["spent_s"] = config, spent_s
        raise SystemExit(0)

    monkeypatch.setattr(seenerf.cli.sessions, "prepare_session", fake_prepare)
    monkeypatch.setattr(seenerf.cli.sessions, "read_manifest", lambda session: None)
    monkeypatch.setattr(seenerf.cli.sessions, "session_bins", lambda session, config: 4)
    monkeypatch.setattr(seenerf.cli.sessions, "fit_session", fake_fit_session)
    parser = argparse.ArgumentParser()
    fit_verb.add_arguments(parser)
    with pytest.raises(SystemExit):
        fit_verb.run(parser.parse_args([str(tmp_path), "--threshold", "0.35"]))
    assert seen["prepared"] == (tmp_path, 4)
    assert seen["spent_s"] == 12.5  # the budget counts the preparation
    assert seen["config"].sensor.threshold == pytest.approx(0.35)
    assert parser.parse_args([str(tmp_path)]).threshold is None  # None: measured
    # A run's saved config.json fits again as it was; options given beside it replace its values.
    from seenerf.model.config import save_config

    save_config(FitConfig.of(threshold=0.25, seed=7, steps=40), tmp_path / "config.json")
    with pytest.raises(SystemExit):
        fit_verb.run(
            parser.parse_args(
                [str(tmp_path), "--config", str(tmp_path / "config.json"), "--seed", "1"]
            )
        )
    config = seen["config"]
    assert (config.sensor.threshold, config.schedule.seed, config.schedule.steps) == (0.25, 1, 40)


def test_a_fits_log_holds_the_preparation_and_its_config_the_software(monkeypatch, tmp_path):
    import seenerf.cli.sessions
    from seenerf.cli.sessions import prepare_and_fit
    from seenerf.data.synthetic import plane_scene

    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=1)

    def fake_prepare(session, b, log=print, camera_calibration=None, threads=0):
        log("measuring the sensor from the recording")
        log("estimating poses (b=2)")
        return 1.0

    monkeypatch.setattr(seenerf.cli.sessions, "prepare_session", fake_prepare)
    monkeypatch.setattr(seenerf.cli.sessions, "read_manifest", lambda session: None)
    monkeypatch.setattr(seenerf.cli.sessions, "session_bins", lambda session, config: 2)
    monkeypatch.setattr("seenerf.train.session_fit.session_bins", lambda session, config: 2)
    monkeypatch.setattr("seenerf.train.session_fit.training_data", lambda *a, **k: scene)
    (tmp_path / "session.json").write_text("{}")
    config = FitConfig.of(steps=2, batch_pixels=8, warm_steps=2, validation_share=0.1)
    shown = []
    result = prepare_and_fit(tmp_path, config, log=shown.append)
    log = (result.run_dir / "log.txt").read_text().splitlines()
    assert "  threads: " in log[0] and " cores" in log[0]  # chosen from the free cores
    assert log[1].endswith("  measuring the sensor from the recording")
    assert log[2].endswith("  estimating poses (b=2)") and "training fast full" in log[3]
    assert shown[1:3] == ["measuring the sensor from the recording", "estimating poses (b=2)"]
    software = json.loads((result.run_dir / "config.json").read_text())["software"]
    assert software["device"] == "cpu" and software["torch"] == torch.__version__
    assert software["seecap"] and software["commit"]
    # The page is made from the session, which this one is not: the fit's results stand anyway.
    assert any(line.startswith("report.html not written") for line in shown)


def test_a_fit_with_a_budget_says_what_its_preparation_should_take_first(monkeypatch, tmp_path):
    import seenerf.cli.sessions
    from davis_io.prepare import preparation_seconds
    from seenerf.cli.sessions import prepare_and_fit

    class Stop(Exception):
        pass

    def fake_prepare(session, b, log=print, camera_calibration=None, threads=0):
        raise Stop

    estimate = preparation_seconds(24_000_000, 16, 5, calibrated=False, posed=False)
    monkeypatch.setattr(seenerf.cli.sessions, "estimate_preparation", lambda folder, b: estimate)
    monkeypatch.setattr(seenerf.cli.sessions, "prepare_session", fake_prepare)
    monkeypatch.setattr(seenerf.cli.sessions, "read_manifest", lambda session: None)
    monkeypatch.setattr(seenerf.cli.sessions, "session_bins", lambda session, config: 4)
    shown = []
    with pytest.raises(Stop):
        prepare_and_fit(tmp_path, FitConfig.of(time_budget_s=600.0, threads=1), log=shown.append)
    assert shown[1] == (
        "budget 600 s: about 19 s to measure the sensor (24.0 M events) and 57 s for poses "
        "(80 latent frames), then training and the final renders in the 523 s left"
    )
    shown.clear()
    with pytest.raises(Stop):
        prepare_and_fit(tmp_path, FitConfig.of(threads=1), log=shown.append)
    assert not [line for line in shown if line.startswith("budget")]  # no budget, no plan


def test_a_stopped_fit_exits_143_with_one_line(monkeypatch, tmp_path, capsys):
    import seenerf.cli.sessions
    from davis_io.cli import main
    from seenerf.errors import TrainingStopped

    def stopped(*args, **kwargs):
        raise TrainingStopped("stopped at step 7 (SIGTERM); checkpoint saved in x", 15)

    monkeypatch.setattr(
        seenerf.cli.sessions,
        "prepare_session",
        lambda session, b, log=print, camera_calibration=None, threads=0: 0.0,
    )
    monkeypatch.setattr(seenerf.cli.sessions, "read_manifest", lambda session: None)
    monkeypatch.setattr(seenerf.cli.sessions, "session_bins", lambda session, config: 4)
    monkeypatch.setattr(seenerf.cli.sessions, "fit_session", stopped)
    assert main(["fit", str(tmp_path), "--quiet"]) == 143
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["seecap: error: fit: stopped at step 7 (SIGTERM); checkpoint saved in x"]
